#include "padae/semi_explicit.hpp"

namespace padae {

namespace {

std::vector<std::pair<int, int>> dense_if_empty(int n, std::vector<std::pair<int, int>> entries) {
  if (!entries.empty()) return entries;
  for (int row = 0; row < n; ++row)
    for (int column = 0; column < n; ++column) entries.emplace_back(row, column);
  return entries;
}

}  // namespace

SemiExplicitSystem::SemiExplicitSystem(std::vector<UnknownKind> kinds,
                                       std::vector<std::pair<int, int>> entries)
    : kinds_(std::move(kinds)),
      pattern_(static_cast<int>(kinds_.size()),
               dense_if_empty(static_cast<int>(kinds_.size()), std::move(entries))) {
  const int n = size();
  diagonal_.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) diagonal_[i] = pattern_.index(i, i);
  equations_.setZero(n);
}

EvalStatus SemiExplicitSystem::load(double t, const Vector& x, const Predicates& p, Load& out) {
  const int n = size();
  equations_.setZero();
  if (equations(t, x, p, equations_) != EvalStatus::ok) return EvalStatus::outside_domain;
  // Differential rows: d/dt x_i - rhs_i = 0, so q_i = x_i and f_i = -rhs_i.
  for (int i = 0; i < n; ++i) {
    if (kinds_[i] == UnknownKind::differential) {
      out.q[i] = x[i];
      out.f[i] = -equations_[i];
    } else if (kinds_[i] == UnknownKind::algebraic) {
      out.f[i] = equations_[i];
    }
  }
  if (!out.jacobian_requested) return EvalStatus::ok;
  jacobian_.assign(static_cast<std::size_t>(pattern_.nonzeros()), 0.0);
  if (!equation_jacobian(t, x, p, jacobian_)) return EvalStatus::outside_domain;
  const auto& starts = pattern_.column_starts();
  const auto& rows = pattern_.row_indices();
  for (int column = 0; column < n; ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k) {
      UnknownKind row_kind = kinds_[rows[k]];
      if (row_kind == UnknownKind::differential) out.df_dx[k] = -jacobian_[k];
      else if (row_kind == UnknownKind::algebraic) out.df_dx[k] = jacobian_[k];
    }
  for (int i = 0; i < n; ++i)
    if (kinds_[i] == UnknownKind::differential) out.dq_dx[diagonal_[i]] = 1.0;
  return EvalStatus::ok;
}

}  // namespace padae
