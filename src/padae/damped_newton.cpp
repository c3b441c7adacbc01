#include "padae/damped_newton.hpp"

#include <cmath>

#include "padae/norms.hpp"

namespace padae {

namespace {

// The smallest fraction of a correction taken: a junction's first correction from d below its
// solution is about e^(d / VT) times d (1e13 at 30 VT).
constexpr double kMinDamping = 1e-14;

// Damped Newton from x on one corrector equation.
class Iteration {
 public:
  Iteration(NewtonMatrix& newton, Statistics& statistics, const CorrectorEquation& equation,
            const Vector& inverse_weight, double tolerance)
      : newton_(newton), statistics_(statistics), equation_(equation), inverse_weight_(inverse_weight),
        tolerance_(tolerance) {}

  NewtonOutcome run(int max_iterations, Vector& x) {
    for (int iteration = 0; iteration < max_iterations; ++iteration) {
      const auto factored = newton_.factor(equation_.t, x, equation_.p, equation_.c);
      if (factored == NewtonMatrix::Outcome::outside_domain) return NewtonOutcome::outside_domain;
      if (factored == NewtonMatrix::Outcome::singular) return NewtonOutcome::singular;
      if (iteration == 0) start_sign_ = newton_.determinant_sign();
      ++statistics_.newton_iterations;
      corrector_correction(newton_, equation_, x, residual_, step_);
      const double norm = weighted_max_norm(step_, inverse_weight_);
      if (!std::isfinite(norm)) return NewtonOutcome::diverged;
      if (norm <= tolerance_) return converge(step_, x);
      double damping = 1, simplified_norm = 0;
      for (;; damping /= 2) {
        if (damping < kMinDamping) return NewtonOutcome::diverged;
        trial_ = x - damping * step_;
        if (newton_.evaluate(equation_.t, trial_, equation_.p) != EvalStatus::ok) continue;
        corrector_correction(newton_, equation_, trial_, residual_, simplified_);
        simplified_norm = weighted_max_norm(simplified_, inverse_weight_);
        if (simplified_norm <= (1 - damping / 4) * norm) break;
        // Within one tolerance unit and no longer shrinking: the round-off floor of a tight
        // tolerance, not a failure.
        if (damping == 1 && norm <= 1) return converge(step_, x);
      }
      x = trial_;
      // Near the solution the simplified correction is the remaining error: taken, it converges.
      if (damping == 1 && simplified_norm <= tolerance_) return converge(simplified_, x);
    }
    return NewtonOutcome::diverged;
  }

 private:
  // The last correction taken; q and f are left evaluated at the solution. A solution where the
  // matrix's determinant has another sign than at the start is across a fold from it, on
  // another branch: refused.
  NewtonOutcome converge(const Vector& correction, Vector& x) {
    if (newton_.determinant_sign() != start_sign_) return NewtonOutcome::diverged;
    x -= correction;
    return newton_.evaluate(equation_.t, x, equation_.p) == EvalStatus::ok ? NewtonOutcome::converged
                                                                           : NewtonOutcome::outside_domain;
  }

  NewtonMatrix& newton_;
  Statistics& statistics_;
  const CorrectorEquation& equation_;
  const Vector& inverse_weight_;
  const double tolerance_;
  int start_sign_ = 0;
  Vector residual_, step_, trial_, simplified_;
};

}  // namespace

void corrector_correction(const NewtonMatrix& newton, const CorrectorEquation& equation, const Vector& x,
                          Vector& residual, Vector& delta) {
  const Load& load = newton.load();
  residual = equation.q_derivative + equation.c * (load.q - equation.q_anchor) + load.f;
  for (int i : newton.auxiliary_unknowns()) residual[i] = x[i] - equation.x_held[i];
  delta = residual;
  newton.solve(delta);
}

NewtonOutcome solve_damped(NewtonMatrix& newton, Statistics& statistics, const CorrectorEquation& equation,
                           const Vector& inverse_weight, double tolerance, int max_iterations, Vector& x) {
  return Iteration(newton, statistics, equation, inverse_weight, tolerance).run(max_iterations, x);
}

}  // namespace padae
