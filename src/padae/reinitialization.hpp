// Consistent re-initialization after an event, and the jump of the state it implies.
//
// For the charge form d/dt q(x) + f(t, x) = 0 a mode change can leave the old charges
// inconsistent with the new algebraic constraints (an ideal switch joining capacitors at
// different voltages; an open switch breaking an inductor's current). The physical state after
// the event is the limit, as h -> 0, of a backward-Euler step of length h from the old charges:
//     q(x+) - q(x-) + h f(t, x+) = 0     (dynamic rows)        f(t, x+) = 0   (algebraic rows)
// Its impulsive unknowns carry the charge (or flux) that moved, so charge is conserved on every
// cut-set and flux on every loop, whatever the topology. padae takes the step with h a few
// ulps of t: below the time resolution, so the state it reaches is the state at t + 0.
// Backward-Euler steps of lengths h, 2h and 4h from the charges after the jump, with h about
// 1e-3 of the integrator's step, settle the algebraic unknowns (impulsive in the first step);
// their extrapolation to h = 0 is the consistent state at t + 0, and the
// right derivative of q is -f there (the BDF restarts at order 1 from it). The first step also
// shows where the new motion is heading (convention (9) applied to the new mode). The settling
// steps are long enough to be well conditioned where the vanishing step is not (a capacitor
// without a DC path: C/h swamps its conductances), and the extrapolation keeps them accurate.
// When Newton fails on the new mode, the paper's continuation in a parameter blends the
// residuals of the old and the new mode.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>

#include "padae/integrator.hpp"
#include "padae/newton_matrix.hpp"

namespace padae {

struct ConsistentState {
  Vector x_impulse;     // the state the vanishing step reaches, impulsive unknowns included
  Vector x;             // consistent state at t + 0
  Vector q;             // q(x)
  Vector q_derivative;  // right derivative of q at t
  Vector q_second_derivative;  // of q at t + 0, from the first settling step (dynamic rows)
  Vector x_derivative;  // right derivative of x, from the look-ahead (for prediction only)
  Vector impulse;       // integral of each unknown over the jump (empty without a jump)
  bool charges_moved = false;  // q changed at the jump beyond round-off
  double t_heading = 0; // a point just after t on the new motion
  Vector x_heading;
};

// Whether each settling step (lengths h, 2h, 4h) keeps its own factorization from one call to
// the next. Dense output keeps them: its rows follow one another in time and mode, so a matrix
// factored for an earlier row is usually still close to the one at the row's state (it is
// refactored where it is not, or where modified Newton contracts slowly on it). Events factor
// afresh on the caller's matrix: the integration never depends on what was factored before.
enum class SettlingFactorizations { fresh, kept };

class Reinitializer {
 public:
  Reinitializer(System& system, NewtonMatrix& newton, Statistics& statistics,
                const Options& options, const Vector& absolute_tolerance,
                SettlingFactorizations settling_factorizations = SettlingFactorizations::fresh);

  // The state after the predicates changed from p_from to p_to at t; x_start already holds
  // the explicit jumps X e. h_reference: a step size typical of the solution near t.
  std::optional<ConsistentState> jump(double t, const Vector& x_start, const Predicates& p_from,
                                      const Predicates& p_to, double h_reference);

  // x(t) with the charges of x_guess and everything else consistent with them: the algebraic
  // unknowns and the hidden algebraic directions (a floating capacitor's common mode) that no
  // error test controls are solved for, not taken from an interpolating polynomial.
  // x_derivative_guess (the polynomial's) predicts the settling steps' motion for Newton.
  std::optional<Vector> project(double t, const Vector& x_guess, const Vector& x_derivative_guess,
                                const Predicates& p, double h_reference);

  const std::string& failure_reason() const { return failure_reason_; }
  int failure_unknown() const { return failure_unknown_; }
  // After a failed jump whose continuation stalled: the state where it stalled, close to the
  // new mode (a mode without a solution, like an ideal switch closing onto a conducting ideal
  // diode, shows there which other predicates must change with it).
  const std::optional<Vector>& stalled_state() const { return stalled_state_; }

 private:
  // Backward Euler of length h from charges q_start, for the blend of modes
  // (1 - lambda) p_from + lambda p_to, evaluated at t_eval; x holds the guess and the result.
  // Newton iterates on `newton`, on the factorization it holds where that is kept and still
  // close to the matrix at x.
  bool backward_euler(NewtonMatrix& newton, double t_eval, double h, const Vector& q_start,
                      const Vector& held, const Predicates& p_from, const Predicates& p_to,
                      double lambda, Vector& x);
  bool backward_euler_with_continuation(NewtonMatrix& newton, double t_eval, double h,
                                        const Vector& q_start, const Predicates& p_from,
                                        const Predicates& p_to, Vector& x);
  // The matrix of settling step 0, 1, 2 (length h, 2h, 4h).
  NewtonMatrix& settling_matrix(int step) {
    return kept_settling_matrices_[step] ? *kept_settling_matrices_[step] : newton_;
  }
  double time_resolution(double t) const;
  double settle_step(double t, double h_reference) const;
  // The consistent state at t + 0 the settling steps reach, and the first of them (length h):
  // where the new motion heads. Newton starts each step from the previous one's state moved by
  // motion_guess (dx/dt) over the difference of their lengths.
  struct Settled {
    Vector x;
    Vector x_first_step;
    double h;
  };
  std::optional<Settled> settle(double t, const Vector& x_plus, const Vector& q_plus,
                                const Predicates& p, double h, const Vector& motion_guess);
  std::optional<ConsistentState> consistent_state(double t, const Vector& x_plus,
                                                  const Settled& settled, const Predicates& p);
  bool derivatives_at(double t, const Predicates& p, ConsistentState& state);

  System& system_;
  NewtonMatrix& newton_;
  Statistics& statistics_;
  const Options& options_;
  const Vector& absolute_tolerance_;
  const SettlingFactorizations settling_factorizations_;
  std::array<std::unique_ptr<NewtonMatrix>, 3> kept_settling_matrices_;  // empty when fresh
  std::string failure_reason_;
  int failure_unknown_ = -1;
  std::optional<Vector> stalled_state_;
  Vector delta_, inverse_weight_;  // backward_euler's, kept so that its iterations do not allocate
};

}  // namespace padae
