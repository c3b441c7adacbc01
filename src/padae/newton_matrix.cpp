#include "padae/newton_matrix.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "padae/norms.hpp"

namespace padae {

namespace {

// A direction is resolved where rounding makes at most this fraction of a correction along it.
constexpr double kResolvedRounding = 1e-2;

void size_load(Load& load, int n, int nonzeros) {
  load.f.setZero(n);
  load.q.setZero(n);
  load.df_dx.assign(static_cast<std::size_t>(nonzeros), 0.0);
  load.dq_dx.assign(static_cast<std::size_t>(nonzeros), 0.0);
}

// Greedy distance-2 colouring: columns that share no row can be perturbed together.
std::vector<std::vector<int>> orthogonal_column_groups(const Pattern& pattern) {
  const int n = pattern.size();
  const auto& starts = pattern.column_starts();
  const auto& rows = pattern.row_indices();
  std::vector<std::vector<int>> columns_of_row(static_cast<std::size_t>(n));
  for (int column = 0; column < n; ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k) columns_of_row[rows[k]].push_back(column);

  std::vector<int> group_of(static_cast<std::size_t>(n), -1);
  std::vector<int> forbidden_by(static_cast<std::size_t>(n), -1);  // group -> last column that forbade it
  std::vector<std::vector<int>> groups;
  for (int column = 0; column < n; ++column) {
    for (int k = starts[column]; k < starts[column + 1]; ++k)
      for (int other : columns_of_row[rows[k]])
        if (group_of[other] >= 0) forbidden_by[group_of[other]] = column;
    int group = 0;
    while (group < static_cast<int>(groups.size()) && forbidden_by[group] == column) ++group;
    if (group == static_cast<int>(groups.size())) groups.emplace_back();
    groups[group].push_back(column);
    group_of[column] = group;
  }
  return groups;
}

}  // namespace

NewtonMatrix::NewtonMatrix(System& system, Statistics& statistics, const Vector& typical)
    : system_(system),
      statistics_(statistics),
      pattern_(system.pattern()),
      lu_(pattern_),
      typical_(typical) {
  const int n = system.size();
  size_load(load_, n, pattern_.nonzeros());
  matrix_.resize(static_cast<std::size_t>(pattern_.nonzeros()));
  dq_dx_.assign(matrix_.size(), 0.0);
  auxiliary_.resize(static_cast<std::size_t>(n));
  diagonal_.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    auxiliary_[i] = system.kind(i) == UnknownKind::auxiliary;
    if (auxiliary_[i]) auxiliary_list_.push_back(i);
    diagonal_[i] = pattern_.index(i, i);
  }
  if (!system.analytic_jacobian()) column_groups_ = orthogonal_column_groups(pattern_);
}

EvalStatus NewtonMatrix::evaluate(double t, const Vector& x, const Predicates& p) {
  load_.f.setZero();
  load_.q.setZero();
  load_.jacobian_requested = false;
  ++statistics_.residual_evaluations;
  return system_.load(t, x, p, load_);
}

EvalStatus NewtonMatrix::load_with_derivatives(double t, const Vector& x, const Predicates& p,
                                               Load& out) {
  // A constant Jacobian loaded in this mode is still in load_: evaluate() loads f and q alone.
  if (&out == &load_ && derivatives_mode_ && *derivatives_mode_ == p) return evaluate(t, x, p);
  const int n = system_.size();
  if (out.f.size() != n) size_load(out, n, pattern_.nonzeros());
  out.f.setZero();
  out.q.setZero();
  std::fill(out.df_dx.begin(), out.df_dx.end(), 0.0);
  std::fill(out.dq_dx.begin(), out.dq_dx.end(), 0.0);
  ++statistics_.jacobians;
  EvalStatus status = EvalStatus::ok;
  if (system_.analytic_jacobian()) {
    out.jacobian_requested = true;
    ++statistics_.residual_evaluations;
    status = system_.load(t, x, p, out);
  } else {
    status = finite_difference_derivatives(t, x, p, out);
  }
  if (&out == &load_) {
    if (status == EvalStatus::ok && system_.constant_jacobian()) derivatives_mode_ = p;
    else derivatives_mode_.reset();
  }
  return status;
}

EvalStatus NewtonMatrix::finite_difference_derivatives(double t, const Vector& x,
                                                       const Predicates& p, Load& out) {
  out.jacobian_requested = false;
  ++statistics_.residual_evaluations;
  if (system_.load(t, x, p, out) != EvalStatus::ok) return EvalStatus::outside_domain;
  const int n = system_.size();
  if (perturbed_.f.size() != n) size_load(perturbed_, n, 0);
  const auto& starts = pattern_.column_starts();
  const auto& rows = pattern_.row_indices();
  const double root_eps = std::sqrt(std::numeric_limits<double>::epsilon());
  Vector shifted = x;
  Vector increment(n);
  for (const auto& group : column_groups_) {
    for (int column : group) {
      double magnitude = std::max(std::abs(x[column]), typical_[column]);
      // Round the increment so that x + increment - x is exactly representable.
      volatile double stepped = x[column] + root_eps * magnitude;
      increment[column] = stepped - x[column];
      shifted[column] = stepped;
    }
    perturbed_.f.setZero();
    perturbed_.q.setZero();
    perturbed_.jacobian_requested = false;
    ++statistics_.residual_evaluations;
    if (system_.load(t, shifted, p, perturbed_) != EvalStatus::ok) return EvalStatus::outside_domain;
    for (int column : group) {
      for (int k = starts[column]; k < starts[column + 1]; ++k) {
        int row = rows[k];
        out.df_dx[k] = (perturbed_.f[row] - out.f[row]) / increment[column];
        out.dq_dx[k] = (perturbed_.q[row] - out.q[row]) / increment[column];
      }
      shifted[column] = x[column];
    }
  }
  return EvalStatus::ok;
}

NewtonMatrix::Outcome NewtonMatrix::factor(double t, const Vector& x, const Predicates& p,
                                           double cj, double keep_within) {
  if (load_with_derivatives(t, x, p, load_) != EvalStatus::ok) return Outcome::outside_domain;
  if (factored_exactly(p, cj)) return keep_within > 0 ? Outcome::kept : Outcome::ok;
  if (keep_within > 0 && drift(p, cj) <= keep_within) return Outcome::kept;
  for (std::size_t k = 0; k < matrix_.size(); ++k) matrix_[k] = loaded_entry(k, cj);
  const Outcome outcome = factor_loaded();
  if (outcome == Outcome::ok) {
    factored_mode_ = p;
    factored_cj_ = cj;
  }
  return outcome;
}

void NewtonMatrix::kept_mismatch(const Vector& d, double cj, Vector& out) const {
  const auto& starts = pattern_.column_starts();
  const auto& rows = pattern_.row_indices();
  out.setZero(pattern_.size());
  for (int column = 0; column < pattern_.size(); ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k)
      out[rows[k]] += (matrix_[k] - loaded_entry(k, cj)) * d[column];
  for (int i : auxiliary_list_) out[i] = 0;
  lu_.solve(out);
}

double NewtonMatrix::drift(const Predicates& p, double cj) const {
  if (factored_cj_ == 0 || factored_mode_ != p) return std::numeric_limits<double>::infinity();
  const auto& starts = pattern_.column_starts();
  const auto& rows = pattern_.row_indices();
  const int n = pattern_.size();
  // row_scale_: the largest |now| of each row, then the largest |factored - now|.
  row_scale_.setZero(2 * n);
  for (int column = 0; column < n; ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k) {
      const double now = loaded_entry(k, cj);
      double& largest = row_scale_[rows[k]];
      largest = std::max(largest, std::abs(now));
      double& difference = row_scale_[n + rows[k]];
      difference = std::max(difference, std::abs(matrix_[k] - now));
    }
  double largest_drift = 0;
  for (int row = 0; row < n; ++row) {
    if (auxiliary_[row] || row_scale_[n + row] == 0) continue;
    largest_drift = std::max(largest_drift, row_scale_[n + row] / row_scale_[row]);
  }
  return largest_drift;
}

EvalStatus NewtonMatrix::charge_determined(double t, const Vector& x, const Predicates& p,
                                           std::vector<char>& out) {
  if (load_with_derivatives(t, x, p, load_) != EvalStatus::ok) return EvalStatus::outside_domain;
  const auto& starts = pattern_.column_starts();
  const auto& rows = pattern_.row_indices();
  const int n = pattern_.size();
  // Per row: its charge's only unknown so far, -1 before any, -2 after a second.
  std::vector<int> only_unknown(static_cast<std::size_t>(n), -1);
  for (int column = 0; column < n; ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k) {
      if (load_.dq_dx[k] == 0) continue;
      int& only = only_unknown[rows[k]];
      only = only == -1 ? column : -2;
    }
  out.assign(static_cast<std::size_t>(n), 0);
  for (int only : only_unknown)
    if (only >= 0) out[only] = 1;
  return EvalStatus::ok;
}

int NewtonMatrix::first_non_finite_row() const {
  for (Eigen::Index i = 0; i < load_.f.size(); ++i)
    if (!std::isfinite(load_.f[i]) || !std::isfinite(load_.q[i])) return static_cast<int>(i);
  return -1;
}

NewtonMatrix::Outcome NewtonMatrix::factor_shifted(double t, const Vector& x, const Predicates& p,
                                                   double shift, double cj) {
  if (load_with_derivatives(t, x, p, load_) != EvalStatus::ok) return Outcome::outside_domain;
  for (std::size_t k = 0; k < matrix_.size(); ++k) matrix_[k] = loaded_entry(k, cj);
  for (int i = 0; i < pattern_.size(); ++i) matrix_[diagonal_[i]] += shift;
  return factor_loaded();
}

NewtonMatrix::Outcome NewtonMatrix::factor_blend(double t, const Vector& x,
                                                 const Predicates& p_from,
                                                 const Predicates& p_to, double lambda,
                                                 double cj) {
  if (load_with_derivatives(t, x, p_from, blend_) != EvalStatus::ok ||
      load_with_derivatives(t, x, p_to, load_) != EvalStatus::ok)
    return Outcome::outside_domain;
  derivatives_mode_.reset();  // load_ now holds the blend's
  const double keep = 1 - lambda;
  load_.f = keep * blend_.f + lambda * load_.f;
  load_.q = keep * blend_.q + lambda * load_.q;
  for (std::size_t k = 0; k < matrix_.size(); ++k) {
    load_.df_dx[k] = keep * blend_.df_dx[k] + lambda * load_.df_dx[k];
    load_.dq_dx[k] = keep * blend_.dq_dx[k] + lambda * load_.dq_dx[k];
    matrix_[k] = loaded_entry(k, cj);
  }
  return factor_loaded();
}

NewtonMatrix::Outcome NewtonMatrix::factor_loaded() {
  factored_cj_ = 0;
  dq_dx_ = load_.dq_dx;
  // Auxiliary unknowns are held: their rows become x_i = held value.
  if (!auxiliary_list_.empty()) {
    const auto& starts = pattern_.column_starts();
    const auto& rows = pattern_.row_indices();
    for (int column = 0; column < pattern_.size(); ++column)
      for (int k = starts[column]; k < starts[column + 1]; ++k)
        if (auxiliary_[rows[k]]) matrix_[k] = 0.0;
    for (int i : auxiliary_list_) matrix_[diagonal_[i]] = 1.0;
  }
  ++statistics_.lu_factorizations;
  return lu_.factor(matrix_) ? Outcome::ok : Outcome::singular;
}

bool NewtonMatrix::within_roundoff(const Vector& v, double tolerances, const Vector& inverse_weight,
                                   double roundoffs, const Vector& x, const Vector& other_terms) const {
  rounding_through_inverse(x, other_terms, roundoff_);
  // A differential unknown's correction beyond its tolerance, to be explained by rounding.
  auto charge_slack = [&](Eigen::Index i) {
    return std::abs(v[i]) > tolerances / inverse_weight[i] && system_.kind(static_cast<int>(i)) == UnknownKind::differential;
  };
  bool any_charge_slack = false;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (std::abs(v[i]) > tolerances / inverse_weight[i] + (auxiliary_[i] ? 0.0 : roundoffs * roundoff_[i]))
      return false;
    any_charge_slack = any_charge_slack || charge_slack(i);
  }
  if (!any_charge_slack) return true;
  // The charges v moves, against the charges its unknowns' tolerances represent.
  const auto& starts = pattern_.column_starts();
  const auto& rows = pattern_.row_indices();
  charge_move_.setZero(pattern_.size());
  for (int column = 0; column < pattern_.size(); ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k) charge_move_[rows[k]] += dq_dx_[k] * v[column];
  Vector charge_tolerance;
  charge_scale(tolerances * inverse_weight.cwiseInverse(), charge_tolerance);
  if ((charge_move_.cwiseAbs().array() > charge_tolerance.array()).any()) return false;
  // The direction must still be resolved: the rounding of a correction of the rounding's own
  // size is a small part of it. Past that (eps C / h above the conductance that ties the
  // direction down) no value along it is better than another, and it would drift.
  Vector rounding_of_rounding;
  rounding_through_inverse(roundoff_, Vector::Zero(roundoff_.size()), rounding_of_rounding);
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (charge_slack(i) && rounding_of_rounding[i] > kResolvedRounding * roundoff_[i]) return false;
  return true;
}

void NewtonMatrix::rounding_through_inverse(const Vector& x, const Vector& other_terms, Vector& out) const {
  Vector& rounding = rounding_;
  rounding = other_terms.cwiseAbs();
  add_absolute_product(matrix_, x, rounding);
  for (int row = 0; row < pattern_.size(); ++row)
    rounding[row] *= auxiliary_[row] ? 0.0 : std::numeric_limits<double>::epsilon();
  // Through J^-1 with row signs that do not cancel systematically, from two sign patterns: rows
  // of equal rounding with the same sign cancel along their difference, the very direction a
  // symmetric circuit leaves to rounding (the leakage mode between the halves of a
  // centre-tapped winding, K = 0.999: rounding moved its current 40 times the one pattern's
  // estimate). Two rows have the same sign in both patterns one time in four.
  out.setZero(pattern_.size());
  Vector& signed_rounding = signed_rounding_;
  for (const std::uint32_t sign_bit : {0x8000u, 0x80000000u}) {
    signed_rounding = rounding;
    for (int row = 0; row < pattern_.size(); ++row)
      if (scrambled(row) & sign_bit) signed_rounding[row] = -signed_rounding[row];
    lu_.solve(signed_rounding);
    out = out.cwiseMax(signed_rounding.cwiseAbs());
  }
}

void NewtonMatrix::charge_scale(const Vector& scale, Vector& out) const {
  out.setZero(pattern_.size());
  add_absolute_product(dq_dx_, scale, out);
}

void NewtonMatrix::add_absolute_product(const std::vector<double>& values, const Vector& v, Vector& out) const {
  const auto& starts = pattern_.column_starts();
  const auto& rows = pattern_.row_indices();
  for (int column = 0; column < pattern_.size(); ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k) out[rows[k]] += std::abs(values[k]) * std::abs(v[column]);
}

}  // namespace padae

namespace padae {

void NewtonMatrix::keep_dynamic_rows(Vector& v) const {
  Vector ones = Vector::Ones(pattern_.size()), charge;
  charge_scale(ones, charge);
  for (int i = 0; i < pattern_.size(); ++i)
    if (charge[i] == 0) v[i] = 0;
}

}  // namespace padae
