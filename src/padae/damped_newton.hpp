// Newton's method on the corrector equation that every BDF-type solve in padae has (a step's
// corrector, and the solution inside a step for dense output):
//     q_derivative + c (q(x) - q_anchor) + f(t, x) = 0,   auxiliary unknowns held at x_held,
// refactored at every iterate and damped by Deuflhard's restricted monotonicity test (NLEQ-ERR):
// an iterate is taken only where the simplified correction J(x_k)^-1 r(x_k+1) has shrunk. It
// reaches a junction's solution from far away (the undamped iteration overshoots by
// e^(distance / VT) and creeps back one VT per iteration) and stays on the solution branch its
// start lies on: where that branch has ended (a fold) the corrections stop shrinking and the
// solve fails, instead of landing on another branch. What damping alone lets through (an iterate
// that jumps over the fold) is refused by the sign of det J, which a fold reverses. The damping
// starts at the fraction of the correction the model accepts (System::newton_step_fraction).
#pragma once

#include "padae/newton_matrix.hpp"

namespace padae {

struct CorrectorEquation {
  double t;
  double c;
  const Vector& q_anchor;
  const Vector& q_derivative;
  const Vector& x_held;  // the auxiliary unknowns' values
  const Predicates& p;
};

// delta = J^-1 r(x), with r from the model's last evaluation (which must have been at x) and J
// the factorization held.
void corrector_correction(const NewtonMatrix& newton, const CorrectorEquation& equation, const Vector& x,
                          Vector& residual, Vector& delta);

enum class NewtonOutcome { converged, diverged, outside_domain, singular };

// The corrections still to come, in units of the last one, before a contraction rate is measured
// (IDA's initial convergence factor).
constexpr double kUnmeasuredConvergenceFactor = 20;

// Solves from x (overwritten by the solution, or by the last iterate on failure). Converged: a
// full correction within `tolerance` in the max norm weighted by inverse_weight, as are the
// corrections its contraction says are still to come (also when the corrections stall within one
// tolerance unit: the round-off floor), with the model's nonlinear currents converged on it
// within rtol (System::currents_converged). branch_sign: the sign of
// det J on the branch sought (a step's corrector knows it from the step's start, which a
// predictor can overshoot past a fold); 0 takes the start's. Each iteration counts in
// statistics.newton_iterations.
NewtonOutcome solve_damped(NewtonMatrix& newton, Statistics& statistics, const CorrectorEquation& equation,
                           const Vector& inverse_weight, double tolerance, double rtol, int max_iterations,
                           Vector& x, int branch_sign = 0);

}  // namespace padae
