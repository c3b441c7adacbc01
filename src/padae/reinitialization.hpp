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
// The extrapolation keeps the charges the steps start from (to within the error test's
// tolerance); where it does not, a mode faster than the steps moved them (the steps see it
// settled), and shorter steps, or else the vanishing step's state, leave that mode to the
// integration. When Newton fails on the new mode, damped Newton takes the same step; when that
// fails too, the paper's continuation in a parameter blends the residuals of the old and the new
// mode.
#pragma once

#include <initializer_list>
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
  // A mode faster than every settling step moves the charges from x: it is left to the
  // integration, whose first step must then damp it (backward Euler, not the trapezoidal rule).
  bool fast_mode_left = false;
  double t_heading = 0; // a point just after t on the new motion
  Vector x_heading;
};

class Reinitializer {
 public:
  // peak_magnitude: each unknown's largest magnitude so far (the error test's peak floor).
  Reinitializer(System& system, NewtonMatrix& newton, Statistics& statistics,
                const Options& options, const Vector& absolute_tolerance, const Vector& peak_magnitude);

  // The state after the predicates changed from p_from to p_to at t; x_start already holds
  // the explicit jumps X e. h_reference: a step size typical of the solution near t.
  std::optional<ConsistentState> jump(double t, const Vector& x_start, const Predicates& p_from,
                                      const Predicates& p_to, double h_reference);

  const std::string& failure_reason() const { return failure_reason_; }
  int failure_unknown() const { return failure_unknown_; }
  // After a failed jump whose continuation stalled: the state where it stalled, close to the
  // new mode (a mode without a solution, like an ideal switch closing onto a conducting ideal
  // diode, shows there which other predicates must change with it).
  const std::optional<Vector>& stalled_state() const { return stalled_state_; }
  // After a failed jump: the state where the new mode could not be evaluated (outside its
  // domain), if that is why it failed. A guard at zero at the event may be on its other side
  // there, as the motion goes on (abs() of a sine starting at 0, under a sqrt).
  const std::optional<Vector>& outside_domain_state() const { return outside_domain_state_; }
  // After a failed jump: the state where the new mode's matrix was singular, if that is why it
  // failed (a current source whose path the mode opens, a loop of ideal elements it closes).
  const std::optional<Vector>& singular_state() const { return singular_state_; }

 private:
  // Backward Euler of length h from charges q_start, for the blend of modes
  // (1 - lambda) p_from + lambda p_to, evaluated at t_eval; x holds the guess and the result.
  bool backward_euler(double t_eval, double h, const Vector& q_start, const Vector& held,
                      const Predicates& p_from, const Predicates& p_to, double lambda, Vector& x);
  // The same step for mode p alone, by damped Newton (padae/damped_newton.hpp).
  bool damped_backward_euler(double t_eval, double h, const Vector& q_start, const Vector& held,
                             const Predicates& p, Vector& x);
  // Newton's weights at x: each unknown's tolerance, never below its round-off.
  void newton_weights(const Vector& x, Vector& inverse_weight) const;
  bool backward_euler_with_continuation(double t_eval, double h, const Vector& q_start,
                                        const Predicates& p_from, const Predicates& p_to,
                                        Vector& x);
  double settle_step(double t, double h_reference) const;
  std::optional<ConsistentState> settle(double t, const Vector& x_plus, const Vector& q_plus,
                                        const Predicates& p, double h);
  bool derivatives_at(double t, const Predicates& p, ConsistentState& state);
  // A failure because the model cannot be evaluated at (t, x): the reason, x, and the unknown
  // whose equation is not finite there in the first of the modes that cannot evaluate it.
  void outside_domain_at(double t, const Vector& x, std::initializer_list<const Predicates*> modes,
                         const char* reason);

  System& system_;
  NewtonMatrix& newton_;
  Statistics& statistics_;
  const Options& options_;
  const Vector& absolute_tolerance_;
  const Vector& peak_magnitude_;
  std::string failure_reason_;
  int failure_unknown_ = -1;
  std::optional<Vector> stalled_state_;
  std::optional<Vector> outside_domain_state_;
  std::optional<Vector> singular_state_;
  Vector delta_, inverse_weight_;  // Newton's correction and weights
};

}  // namespace padae
