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
//    current sources cut them off, those sources (one whose current reads the voltage of a node
//    it connects, G1 a 0 a 0, is a conductance: a path);
//  - voltage sources (E, H, B with V= included) form a loop, with inductors too for the
//    operating point, naming the loop's elements;
//  - for the operating point, which holds them, a .ic voltage is on a node those fix already
//    (ModelError::initial_condition() names its node).
// Switches and diodes count as paths (either state may hold); an RON = 0 switch closing a
// loop of voltage sources is only found when it happens (the integrator reports it).
void check_structure(const Model& model, StartKind start);

// Throws ModelError, at the first K card of the group, when a group of coupled inductors has an
// inductance matrix (their flux rows' -dq/di) that is not positive semidefinite: couplings each
// within |k| <= 1 can still make windings that store negative energy (k12 = k13 = 0.9,
// k23 = -0.9), whose currents grow without bound. Perfect coupling (k = 1) passes. Nothing
// is done for a circuit without K.
void check_inductance_matrices(Model& model);

// The same checks in one mode (the start's switch and diode states): closed RON = 0 switches
// and diodes count as voltage sources, open ROFF = infinite ones as no connection, so a loop
// they close or a node they isolate is reported before the run.
void check_mode_structure(const Model& model, StartKind start, const padae::Predicates& mode);

// The same checks in a mode the run reached (capacitors conduct, inductors do not): what they
// find, or empty. A mode without a consistent state after an event may be singular so (a current
// source in series with an ideal switch that opened, sources in a loop an ideal switch closed).
std::string mode_structure_fault(const Model& model, const padae::Predicates& mode);

// After a start failed: when the start's equations are linear in the given mode (the Newton
// matrix, df/dx for the operating point or df/dx + dq/dx / time_scale for uic, is the same at two
// points) and that matrix is singular (full-pivoting LU after row and column equilibration),
// the message names the unknowns of a null vector, e.g. "... do not determine v(a), i(e1)".
// Empty when the matrix is regular, the equations are nonlinear (their failure is not bad
// input), or the circuit has more than kSingularCheckMaxUnknowns unknowns (dense LU).
constexpr int kSingularCheckMaxUnknowns = 2000;
std::string singular_linear_equations(Model& model, StartKind start, const padae::Predicates& mode, double t,
                                      double time_scale);

}  // namespace mna
