#include "padae/reinitialization.hpp"

#include <cmath>
#include <limits>

namespace padae {

namespace {

constexpr int kMaxIterations = 100;          // junctions far from their solution need many
constexpr double kConvergedNorm = 1e-3;     // Newton correction, in tolerance units
constexpr double kRefactorRate = 0.1;       // refactor when Newton contracts slower than this
constexpr double kEps = std::numeric_limits<double>::epsilon();

}  // namespace

Reinitializer::Reinitializer(System& system, NewtonMatrix& newton, Statistics& statistics,
                             const Options& options, const Vector& absolute_tolerance)
    : system_(system),
      newton_(newton),
      statistics_(statistics),
      options_(options),
      absolute_tolerance_(absolute_tolerance) {}

bool Reinitializer::backward_euler(double t_eval, double h, const Vector& q_start,
                                   const Vector& held, const Predicates& p_from,
                                   const Predicates& p_to, double lambda, Vector& x) {
  const double cj = 1 / h;
  const bool blended = lambda < 1;
  auto factor = [&]() {
    return blended ? newton_.factor_blend(t_eval, x, p_from, p_to, lambda, cj)
                   : newton_.factor(t_eval, x, p_to, cj);
  };
  auto evaluate = [&]() {
    if (!blended) return newton_.evaluate(t_eval, x, p_to) == EvalStatus::ok;
    return newton_.factor_blend(t_eval, x, p_from, p_to, lambda, cj) == NewtonMatrix::Outcome::ok;
  };

  double previous_norm = std::numeric_limits<double>::infinity();
  bool refactor = true;
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    if (refactor) {
      auto outcome = factor();
      if (outcome != NewtonMatrix::Outcome::ok) {
        failure_reason_ = outcome == NewtonMatrix::Outcome::singular
                              ? "the circuit equations are singular in the new mode"
                              : "the model cannot be evaluated in the new mode";
        failure_unknown_ = outcome == NewtonMatrix::Outcome::singular ? newton_.singular_column() : -1;
        return false;
      }
    } else if (!evaluate()) {
      failure_reason_ = "the model cannot be evaluated in the new mode";
      return false;
    }
    ++statistics_.newton_iterations;
    const Load& load = newton_.load();
    Vector delta = (load.q - q_start) * cj + load.f;
    for (int i : newton_.auxiliary_unknowns()) delta[i] = x[i] - held[i];
    newton_.solve(delta);
    x -= delta;
    // The tolerance never asks for less than round-off in x.
    Vector inverse_weight =
        ((options_.rtol + 100 * kEps) * x.cwiseAbs() + absolute_tolerance_).cwiseInverse();
    double norm = 0;
    int worst = -1;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      double scaled = std::abs(delta[i]) * inverse_weight[i];
      if (!(scaled <= norm)) norm = scaled, worst = static_cast<int>(i);
    }
    if (!std::isfinite(norm)) {
      failure_reason_ = "Newton's method diverges in the new mode";
      failure_unknown_ = worst;
      return false;
    }
    if (norm <= kConvergedNorm) return true;
    double rate = norm / previous_norm;
    refactor = rate > kRefactorRate;
    previous_norm = norm;
    failure_unknown_ = worst;
  }
  failure_reason_ = "Newton's method does not converge in the new mode";
  return false;
}

bool Reinitializer::backward_euler_with_continuation(double t_eval, double h,
                                                     const Vector& q_start,
                                                     const Predicates& p_from,
                                                     const Predicates& p_to, Vector& x) {
  const Vector guess = x;
  if (backward_euler(t_eval, h, q_start, guess, p_from, p_to, 1.0, x)) return true;
  if (p_from == p_to) return false;
  // Continuation in a parameter (the paper's remedy): from the old mode, whose solution is
  // near x, to the new one.
  x = guess;
  if (!backward_euler(t_eval, h, q_start, guess, p_from, p_to, 0.0, x)) return false;
  double lambda = 0, increment = 0.25;
  while (lambda < 1) {
    double next = std::min(1.0, lambda + increment);
    Vector trial = x;
    if (backward_euler(t_eval, h, q_start, guess, p_from, p_to, next, trial)) {
      x = trial;
      lambda = next;
      increment = std::min(2 * increment, 1.0);
    } else if ((increment *= 0.5) < 1e-6) {
      failure_reason_ = "no consistent state in the new mode (continuation stalled at " +
                        std::to_string(lambda) + ")";
      return false;
    }
  }
  return true;
}

std::optional<ConsistentState> Reinitializer::jump(double t, const Vector& x_start,
                                                   const Predicates& p_from,
                                                   const Predicates& p_to, double h_reference) {
  if (newton_.evaluate(t, x_start, p_from) != EvalStatus::ok) {
    failure_reason_ = "the model cannot be evaluated at the event";
    return std::nullopt;
  }
  const Vector q_before = newton_.load().q;
  const double h_impulse = 16 * kEps * std::max(std::abs(t), options_.time_scale);
  Vector x_plus = x_start;
  if (!backward_euler_with_continuation(t, h_impulse, q_before, p_from, p_to, x_plus))
    return std::nullopt;
  auto consistent = derivatives(t, x_plus, p_to, h_reference);
  if (!consistent) return consistent;
  consistent->impulse = h_impulse * x_plus;
  // A jump moves q by far more than the smooth motion does over the impulse step.
  for (Eigen::Index i = 0; i < q_before.size(); ++i) {
    double moved = std::abs(consistent->q[i] - q_before[i]);
    double smooth = 10 * h_impulse * std::abs(consistent->q_derivative[i]);
    double scale = std::abs(consistent->q[i]) + std::abs(q_before[i]);
    if (moved > smooth + 1e-10 * scale + std::numeric_limits<double>::min()) consistent->charges_moved = true;
  }
  return consistent;
}

std::optional<ConsistentState> Reinitializer::derivative_only(double t, const Vector& x,
                                                              const Predicates& p,
                                                              double h_reference) {
  return derivatives(t, x, p, h_reference);
}

std::optional<ConsistentState> Reinitializer::derivatives(double t, const Vector& x_plus,
                                                          const Predicates& p,
                                                          double h_reference) {
  if (newton_.evaluate(t, x_plus, p) != EvalStatus::ok) {
    failure_reason_ = "the model cannot be evaluated after the event";
    return std::nullopt;
  }
  ConsistentState state;
  const Vector q_plus = newton_.load().q;  // a copy: the Newton iterations below reload
  // Algebraic unknowns may carry impulses in x_plus; their consistent values are those a very
  // short step reaches (within 1e-8 of a step of t).
  const double t_floor = std::max(std::abs(t), options_.time_scale);
  const double h_settle = std::max(1e-8 * h_reference, 1e4 * kEps * t_floor);
  Vector x_settled = x_plus;
  if (!backward_euler_with_continuation(t + h_settle, h_settle, q_plus, p, p, x_settled))
    return std::nullopt;
  state.x_impulse = x_plus;
  state.x = x_plus;
  for (int i = 0; i < system_.size(); ++i)
    if (system_.kind(i) == UnknownKind::algebraic) state.x[i] = x_settled[i];
  if (newton_.evaluate(t, state.x, p) != EvalStatus::ok) {
    failure_reason_ = "the model cannot be evaluated after the event";
    return std::nullopt;
  }
  state.q = newton_.load().q;
  state.q_derivative = -newton_.load().f;
  newton_.keep_dynamic_rows(state.q_derivative);
  // Its truncation error in h x' is about 1e-3 of the first step's own local error.
  const double h_look = std::max(1e-3 * h_reference, 1e6 * kEps * t_floor);
  state.x_heading = state.x;
  if (!backward_euler_with_continuation(t + h_look, h_look, state.q, p, p, state.x_heading))
    return std::nullopt;
  state.t_heading = t + h_look;
  state.x_derivative = (state.x_heading - state.x) / h_look;
  return state;
}

}  // namespace padae
