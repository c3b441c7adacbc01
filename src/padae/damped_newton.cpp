#include "padae/damped_newton.hpp"

#include <cmath>

#include "padae/norms.hpp"

namespace padae {

namespace {

// The smallest fraction of a correction taken: a junction's first correction from d below its
// solution is about e^(d / VT) times d (1e13 at 30 VT).
constexpr double kMinDamping = 1e-14;

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
                           const Vector& inverse_weight, double tolerance, double rtol, int max_iterations,
                           Vector& x, int branch_sign) {
  Vector residual, step, trial, simplified;
  // The last correction taken; q and f are left evaluated at the solution. A solution where the
  // matrix's determinant has another sign than on the branch is across a fold from it, on
  // another branch: refused.
  auto converge = [&](const Vector& correction) {
    if (newton.determinant_sign() != branch_sign) return NewtonOutcome::diverged;
    x -= correction;
    return newton.evaluate(equation.t, x, equation.p) == EvalStatus::ok ? NewtonOutcome::converged
                                                                        : NewtonOutcome::outside_domain;
  };
  // The last correction taken in full: its contraction to the next one measures the rate.
  double full_norm = 0;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    const auto factored = newton.factor(equation.t, x, equation.p, equation.c);
    if (factored == NewtonMatrix::Outcome::outside_domain) return NewtonOutcome::outside_domain;
    if (factored == NewtonMatrix::Outcome::singular) return NewtonOutcome::singular;
    if (branch_sign == 0) branch_sign = newton.determinant_sign();
    ++statistics.newton_iterations;
    corrector_correction(newton, equation, x, residual, step);
    const double norm = weighted_max_norm(step, inverse_weight);
    if (!std::isfinite(norm)) return NewtonOutcome::diverged;
    // Converged where this correction and the ones still to come are within the tolerance: those
    // rate / (1 - rate) times this one (IDA's test), the rate from the last full correction;
    // without one, kUnmeasuredConvergenceFactor times. A correction within the tolerance says
    // nothing of the residual where it lands: from a predictor where a junction conducted amps
    // (boost.cir at its turn-off, rtol 2e-2) a first correction of 0.28 tolerance units led to
    // one of 0.35, and, taken as converged, to 12 mA through the blocked junction.
    const double rate = full_norm > 0 ? norm / full_norm : 1;
    const double to_come = (rate < 1 ? rate / (1 - rate) : kUnmeasuredConvergenceFactor) * norm;
    trial = x - step;
    if (norm <= tolerance && to_come <= tolerance && newton.currents_converged(x, trial, rtol)) return converge(step);
    // Damping starts where the model's limits put it (a junction's exponential), then halves.
    double damping = newton.step_fraction(x, x - step), simplified_norm = 0;
    for (;; damping /= 2) {
      if (damping < kMinDamping) return NewtonOutcome::diverged;
      trial = x - damping * step;
      if (newton.evaluate(equation.t, trial, equation.p) != EvalStatus::ok) continue;
      corrector_correction(newton, equation, trial, residual, simplified);
      simplified_norm = weighted_max_norm(simplified, inverse_weight);
      if (simplified_norm <= (1 - damping / 4) * norm) break;
      // No longer shrinking, within one tolerance unit or within what rounding makes of the
      // correction (index 2: a source's current through capacitors, C/h per ulp of their
      // voltages): the round-off floor, not a failure.
      if (damping == 1 &&
          (norm <= 1 || newton.within_roundoff(step, 1, inverse_weight, 1, x,
                                               equation.q_derivative.cwiseAbs() + equation.c * equation.q_anchor.cwiseAbs())) &&
          newton.currents_converged(x, trial, rtol))
        return converge(step);
    }
    // The simplified correction is on the matrix at the last iterate, which can be far stiffer
    // than the one at the trial (a junction that has since turned off): however small, it does
    // not prove convergence, the next fresh correction does.
    x = trial;
    full_norm = damping == 1 ? norm : 0;
  }
  return NewtonOutcome::diverged;
}

}  // namespace padae
