// The consistent state a transient starts from.
#pragma once

#include <string>

#include "mna/model.hpp"
#include "padae/integrator.hpp"

namespace mna {

struct Start {
  bool ok = false;
  Vector x;
  padae::Predicates p;
  std::string message;      // why no start was found
  int worst_unknown = -1;   // the unknown to blame, if any
};

// Without uic: the DC operating point at t0 (sources at their t0 values, as ngspice's transient
// op does) with the predicates iterated to a fixed point; .ic node voltages are held during it
// (ngspice's semantics) and released for the transient; .nodeset voltages are where Newton
// starts. Switch ON/OFF seeds the modes.
// With uic: x0 from IC= and .ic (everything else 0), modes from ON/OFF; the integrator's
// initialization then makes it consistent (algebraic unknowns solved, charges kept).
Start find_start(Model& model, double t0, bool use_initial_conditions, const padae::Options& options);

}  // namespace mna
