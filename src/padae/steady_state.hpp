// Steady state (DC operating point) of a predicate DAE: f(t, x, p) = 0 with dq/dt = 0, and the
// predicates made consistent with the solution (p = P(t, x), iterated to a fixed point).
#pragma once

#include <string>

#include "padae/integrator.hpp"

namespace padae {

struct SteadyState {
  bool converged = false;
  Vector x;
  Predicates p;
  std::string message;     // why it failed
  int worst_unknown = -1;  // the unknown whose Newton correction did not settle, if any
};

// Newton from x_guess (damped), falling back to pseudo-transient continuation; p0 empty means
// "from the guards at x_guess".
SteadyState steady_state(System& system, double t, const Vector& x_guess, const Predicates& p0,
                         const Options& options);

}  // namespace padae
