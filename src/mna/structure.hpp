// Structural singularity checks before a run, on the circuit graph alone (no numbers): they
// name the nodes and elements at fault instead of letting the linear solver fail later.
#pragma once

#include "mna/model.hpp"

namespace mna {

enum class StartKind {
  operating_point,     // DC op first: capacitors are open, inductors shorts
  initial_conditions,  // uic: the transient starts at once
};

// Throws ModelError when
//  - a node has no path to ground (DC path for the operating point: not through capacitors or
//    current sources; any path but current sources for uic), naming the nodes and, when
//    current sources cut them off, those sources;
//  - voltage sources (E, H, B with V= included) form a loop, with inductors too for the
//    operating point, naming the loop's elements.
// Switches and diodes count as paths (either state may hold); an RON = 0 switch closing a
// loop of voltage sources is only found when it happens (the integrator reports it).
void check_structure(const Model& model, StartKind start);

// The same checks in one mode (the start's switch and diode states): closed RON = 0 switches
// and diodes count as voltage sources, open ROFF = infinite ones as no connection, so a loop
// they close or a node they isolate is reported before the run.
void check_mode_structure(const Model& model, StartKind start, const padae::Predicates& mode);

}  // namespace mna
