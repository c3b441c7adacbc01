// The predicate-DAE integrator: variable-order, variable-step BDF (orders 1-5, fixed-leading-
// coefficient form as in DASSL/IDA) applied to the charge-oriented form of system.hpp, with
// exact event location, jumps and consistent re-initialization. The trapezoidal rule is the
// alternative for lossless oscillators, which BDF damps.
//
// Use, one step at a time (the caller writes output and decides what to do next):
//
//     padae::Integrator integrator(system, options);
//     integrator.initialize(t0, x0);            // or initialize(t0, x0, p0)
//     while (integrator.time() < t_end) {
//       auto outcome = integrator.step(t_end);
//       if (outcome.kind == padae::StepKind::failed) ...;
//       ...                                     // output integrator.state()
//     }
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "padae/system.hpp"

namespace padae {

// How the error test combines the weighted local errors of the dynamic quantities: root-mean-
// square (IDA's, the default) or the largest (each held to its tolerance; stricter on large
// circuits). Newton's convergence test always takes the largest.
enum class ErrorNorm { rms, max };

// The integration formula between events.
//   bdf:          variable order 1-5 (Gear). L-stable at low order: a stiff mode decays at once,
//                 but an undamped oscillation loses amplitude (a lossless LC tank, about 3e-5 per
//                 period at rtol 1e-3).
//   trapezoidal:  order 2, A-stable and without damping: an undamped oscillation keeps its
//                 amplitude for any step (phase error only). A stiff mode is not damped either
//                 (it alternates in sign), so this is for oscillators, not for stiff circuits.
//                 Each (re)start begins, as bdf's does, with a step of this rule from the
//                 re-initialization's derivative.
enum class Method { bdf, trapezoidal };

// The smallest rtol the integrator uses; a smaller one is raised to it. Below a few units of
// round-off the error test asks for less than double precision resolves, and only the steps on
// which round-off happens to pass it are accepted: at rtol 1e-16 (vntol 1e-18 V) the relaxation
// oscillator took 5 million steps, with 3 million rejected, to reach 1.7e-5 s of its 1e-2 s; at
// 2.3e-16 it finishes in 9,056.
inline constexpr double kSmallestRtol = 4 * std::numeric_limits<double>::epsilon();

struct Options {
  double rtol = 1e-4;              // at least kSmallestRtol
  double atol = 1e-6;              // default absolute tolerance, see System::absolute_tolerance
  // The error test holds each unknown to rtol * max(|x_i|, peak_floor * peak_i) + atol_i, peak_i
  // the largest |x_i| so far: a signal passing through zero is then not resolved far below its
  // own scale (an amp-scale inductor current near 0 A against an atol of picoamperes).
  // A floor below 256 eps / rtol is raised to that: the round-off of an order-5 estimate.
  // 0 (the default): rtol |x_i| + atol_i, IDA's test. Newton's convergence test is unchanged.
  double peak_floor = 0.0;
  ErrorNorm norm = ErrorNorm::rms;
  Method method = Method::bdf;
  int max_order = 5;               // for bdf (trapezoidal is order 2)
  double initial_step = 0.0;       // 0: chosen from the tolerances
  double max_step = 0.0;           // 0: unlimited
  double min_step = 0.0;           // 0: from the time scale and round-off
  double time_scale = 1.0;         // characteristic length of the run (tstop - t0): sets h_min
  int max_event_iterations = 50;   // predicate fixed-point iterations at one event
  int max_events_in_burst = 100;   // consecutive events within the time resolution: accumulation
};

// The shortest time step that still advances t: a few ulps of t, and near t = 0 1e-24 of the
// run. Below it a step's end rounds to within a few ulps of its start.
inline double time_resolution(double t, const Options& options) {
  return std::max(16 * std::numeric_limits<double>::epsilon() * std::abs(t), 1e-24 * options.time_scale);
}

struct Statistics {
  long steps = 0;                  // accepted steps
  long rejected_error_test = 0;
  long rejected_newton = 0;
  long rejected_domain = 0;        // model evaluations outside the domain (IER)
  long retaken_at_kinks = 0;       // steps redone at order 1 (System::kinks)
  long residual_evaluations = 0;
  long newton_iterations = 0;
  long jacobians = 0;
  long lu_factorizations = 0;
  long events = 0;                 // state events (predicate flips) handled
  long time_events = 0;            // source corners a step ended on (passed ones not counted)
  long jumps = 0;                  // events at which the state jumped
  // Points inside a step (event location, output rows) where Newton found no solution: the
  // interpolating polynomial's x stands in, its algebraic unknowns possibly off by more than
  // the tolerance.
  long unsolved_points = 0;
  // Steps accepted at the time resolution although their error test failed: a transient faster
  // than any step t can represent (see Integrator::unresolved_transient).
  long unresolved_steps = 0;
};

// Where steps first had to pass over a transient faster than the time resolution.
struct UnresolvedTransient {
  double t;                          // the first such step's start
  double resolution;                 // the minimum step there
  int unknown;                       // the unknown whose error was worst
};

// A predicate change at an event.
struct PredicateFlip {
  int predicate;
  bool from;
  bool to;
};

// Why a step ended.
enum class StepKind {
  accepted,    // an ordinary step
  event,       // ended at a located predicate change; last_event() tells which
  time_event,  // ended exactly at a time event (source corner)
  stop,        // reached t_stop exactly
  failed,      // could not continue; failure() tells where and why
};

struct StepOutcome {
  StepKind kind;
  double t;
};

struct EventRecord {
  double t = 0;
  std::vector<PredicateFlip> flips;  // all flips, in order, including those of the fixed point
  Vector x_before;                   // x(t - 0)
  Vector x_after;                    // x(t + 0), consistent with the new predicates
  // The integral of each unknown over the jump: for a branch current, the charge it carried
  // impulsively (for a node voltage, the flux). Zero where nothing was impulsive. With it a
  // model can account the energy a jump dissipated (sources deliver V * charge).
  Vector impulse;
  bool jumped = false;               // x_after differs from x_before in a dynamic quantity
  int iterations = 0;                // predicate fixed-point iterations
};

struct Failure {
  double t;
  std::string reason;
  int unknown = -1;                  // the unknown that was worst, when one is to blame
  std::string diagnosis = {};        // what the failure's figures say of its cause, if anything
};

class Integrator {
 public:
  Integrator(System& system, Options options);
  ~Integrator();
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  // Starts at (t0, x0) with the predicates the guards give (or the given ones), makes the state
  // consistent (jump projection + algebraic re-initialization, predicate fixed point).
  // Returns false, with failure() set, when no consistent state is found.
  bool initialize(double t0, const Vector& x0);
  bool initialize(double t0, const Vector& x0, const Predicates& p0);

  // One step toward t_stop; never past it.
  StepOutcome step(double t_stop);

  double time() const;
  const Vector& state() const;            // x at time()
  const Predicates& predicates() const;   // p for the next step
  int order() const;                      // order of the last step
  double step_size() const;               // size of the last step
  // x(t) for t inside the last step from its interpolating polynomial: cheap, but the unknowns
  // the error test does not control can be far off on it.
  Vector interpolate(double t) const;
  // Dense output for writing: the BDF step from the last step's start to t (dense_output.hpp),
  // so that the unknowns the error test does not control (algebraic ones, hidden algebraic
  // directions) are consistent. Falls back to the interpolating polynomial where Newton fails.
  // The interpolating polynomial itself serves for unknowns that are functions of one charge
  // each (the error test controls them), and for others where it is as accurate as that
  // solution: where the step vouches for it (its predictor and the one before within the
  // tolerance, and its local error's response in x too), else where a solve at the step's
  // midpoint confirms it; elsewhere interpolants of that solution serve where checks certify
  // them (row_refinement.hpp).
  Vector dense_output(double t);
  // The same for the listed unknowns only: the polynomial serves more often, and is evaluated
  // for them alone. The other entries are not computed. Valid until the next call.
  const Vector& dense_output(double t, std::span<const int> unknowns);

  const EventRecord& last_event() const;
  const Failure& failure() const;
  const Statistics& statistics() const;
  // The first transient the steps passed over unresolved (Statistics::unresolved_steps), if any.
  const std::optional<UnresolvedTransient>& unresolved_transient() const;
  // The Newton work of dense_output(), counted apart: writing never changes the integration.
  const Statistics& output_statistics() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace padae
