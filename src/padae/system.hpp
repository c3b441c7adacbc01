// The mathematical contract between a model and the integrator: a predicate-parameterized
// DAE in charge-oriented form (see shared/docs/predicate-dae.md):
//
//     d/dt q(x, p) + f(t, x, p) = 0            x in R^n, p in {0,1}^K
//     p_k = (guard_k(t, x) > 0)                 the predicates
//     x(t_i + 0) = x(t_i - 0) + X(t_i - 0) e    jumps at events, e_k = +1 (0 -> 1) or -1 (1 -> 0)
//
// For every fixed p, f and q are smooth. Rows whose q depends on x are dynamic (their q carries
// memory: for circuits, capacitor charges and inductor fluxes); the other rows are algebraic.
// The paper's semi-explicit forms (3) and (5) are the special case q_i(x) = x_i for the
// differential rows and f = -rhs (see semi_explicit.hpp).
//
// Models never see the step size or the method: they load f, q and their derivatives only.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

#include "padae/pattern.hpp"

namespace padae {

using Vector = Eigen::VectorXd;
// The predicate vector p, one 0/1 entry per predicate.
using Predicates = std::vector<std::uint8_t>;

enum class UnknownKind : std::uint8_t {
  differential,  // integrated; error-tested through the dynamic rows' q
  algebraic,     // determined by the equations at each instant
  auxiliary,     // piecewise constant: changed only by jumps at events, never integrated (paper, 5)
};

// Result of a model evaluation, like the paper's IER flag: outside its domain a model says so
// and the integrator cuts the step instead of failing.
enum class EvalStatus : std::uint8_t { ok, outside_domain };

// What a model loads at (t, x, p). The integrator owns the storage and sizes it.
struct Load {
  Vector f;                    // f(t, x, p), length n
  Vector q;                    // q(x, p), length n
  std::vector<double> df_dx;   // values on pattern(), when jacobian_requested
  std::vector<double> dq_dx;   // values on pattern(), when jacobian_requested
  bool jacobian_requested = false;
};

// Non-zero entries of the jump matrix X (n x K): column `predicate`, row `row`.
struct JumpEntry {
  int row;
  int predicate;
  double value;
};

class System {
 public:
  virtual ~System() = default;

  virtual int size() const = 0;
  virtual UnknownKind kind(int unknown) const = 0;
  virtual const Pattern& pattern() const = 0;

  // Loads f, q (and, when out.jacobian_requested, df/dx and dq/dx on the pattern; the arrays
  // arrive zeroed). Rows of auxiliary unknowns must be left untouched.
  virtual EvalStatus load(double t, const Vector& x, const Predicates& p, Load& out) = 0;

  // Whether load() provides exact derivatives; if not, the integrator differentiates f and q
  // by finite differences on the pattern.
  virtual bool analytic_jacobian() const { return true; }

  // Whether df/dx and dq/dx depend on p alone (f and q affine in x in every mode: a circuit of
  // linear elements and switches). A solver then loads them once per mode and refactors only
  // when the mode or the coefficient of dq/dx changes; it loads f and q alone at every other
  // point.
  virtual bool constant_jacobian() const { return false; }

  // Predicates. guard_k(t, x) > 0 <=> p_k; a guard must be continuous in t and x for fixed
  // auxiliary unknowns, so that its sign change can be located.
  virtual int predicate_count() const { return 0; }
  virtual EvalStatus guards(double t, const Vector& x, Vector& out) const {
    (void)t, (void)x, (void)out;
    return EvalStatus::ok;
  }

  // Kinks: functions of x whose sign change marks where the model, though smooth, turns
  // abruptly (a junction's current through zero, its conductance falling a millionfold). Steps
  // cross them; but an unknown that a stiff mode ties to a derivative (a node held only by a
  // leakage, at L di/dt of the inductor it carries) takes the BDF formula's derivative, and a
  // formula of order > 1 whose history reaches back across the kink overshoots it. The
  // integrator retakes such a step at order 1 (Integrator::Impl::kink_spoils_derivative).
  virtual int kink_count() const { return 0; }
  virtual void kinks(const Vector& x, Vector& out) const { (void)x, (void)out; }

  // Jumps (form (5)). Only called at events, and only when has_jumps().
  // Appends the non-zeros of X(t, x, p) to `out` (which arrives empty).
  virtual bool has_jumps() const { return false; }
  virtual void jump_matrix(double t, const Vector& x, const Predicates& p,
                           std::vector<JumpEntry>& out) const {
    (void)t, (void)x, (void)p, (void)out;
  }

  // Time events known in advance (source corners): the first one strictly after t, or +inf.
  // The integrator ends a step exactly there and restarts at order 1, unless the corner cannot
  // bend the solution (see time_event_rows).
  virtual double next_time_event(double t) const {
    (void)t;
    return std::numeric_limits<double>::infinity();
  }
  // The rows whose time dependence has the corner next_time_event(t), appended to `rows`; false
  // when not known. Rows that share no block of the pattern with a differential unknown (a gate
  // drive read only by guards) cannot bend the solution: the integrator steps across such a
  // corner and only samples the guards there.
  virtual bool time_event_rows(double t, std::vector<int>& rows) const {
    (void)t, (void)rows;
    return false;
  }

  // Newton's step from x to x_next, limited where the model knows its nonlinearity: the largest
  // fraction of the step it accepts (1: all of it). A junction's exponential, linearized in
  // reverse bias, sends the next iterate far into forward conduction; SPICE limits the junction
  // voltage there (pnjlim), padae scales the whole step to that limit. Newton converges only on
  // a whole step.
  virtual double newton_step_fraction(const Vector& x, const Vector& x_next) const {
    (void)x, (void)x_next;
    return 1;
  }
  // SPICE's device convergence test, on Newton's last correction from x_before to x_after:
  // whether every current the model knows to be nonlinear (a junction's) is at x_after within
  // rtol (of the larger) plus its absolute tolerance of its linearization at x_before. Unknowns
  // within their tolerances can leave an exponential far from its solution: at rtol 2e-2 an 18 V
  // node's tolerance is 9 N VT, a factor of 8000 in a junction's current.
  virtual bool currents_converged(const Vector& x_before, const Vector& x_after, double rtol) const {
    (void)x_before, (void)x_after, (void)rtol;
    return true;
  }

  // Only changes of q enter the equations, so q may be measured from any reference. A row sums
  // the charges of the elements at a node, and rounds to the largest: a junction holding 1e-4 C
  // rounds each of its two rows by about 1e-20 C, differently, and a network connected to the
  // rest only by inductors (a rectifier bridge fed from inductive sources) sees the difference as
  // charge created on it, a current of 1e-20 C / h that at the picosecond steps of a start swamps
  // the network's tolerance. The integrator calls this at every (re)start, with the state it starts
  // from; a model may then load each element's charge as its change from its value at (x, p),
  // rows rounding to the size of the changes. Returns whether it did (the integrator then
  // shifts the charges it holds by the old q(x, p)).
  virtual bool measure_charges_from(double t, const Vector& x, const Predicates& p) {
    (void)t, (void)x, (void)p;
    return false;
  }

  // Unknown scale for the tolerance: the absolute tolerance of unknown i in its own units.
  // Default: Options::atol for all.
  virtual double absolute_tolerance(int unknown, double default_atol) const {
    (void)unknown;
    return default_atol;
  }
};

}  // namespace padae
