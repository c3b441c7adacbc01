// Variable-order variable-step BDF in fixed-leading-coefficient form (Brenan, Campbell and
// Petzold; the algorithm of DASSL and SUNDIALS IDA), applied to d/dt q(x) + f(t, x) = 0: the
// history is kept both for x (to predict Newton's starting point) and for q (the quantity the
// BDF formula differentiates, so charge is conserved, and the one whose error is tested).
//
// A step reads: choose h -> set coefficients -> predict -> correct (modified Newton) ->
// error test -> accept (complete step, choose order and h) or reject (restore, shrink) ->
// look for predicate changes in the step -> handle an event (locate, jump, re-initialize,
// restart).
//
// A (re)start has one point and its derivative q' (from the re-initialization): the first step
// is the trapezoidal rule, and the quadratic through both points with the slope at the second
// lets the BDF go on at order 2 (backward Euler, IDA's start, makes a first-order error h^2 q''/2
// of one sign at every restart of a periodic circuit, which adds up over the periods).
//
// The trapezoidal method shares all of it but the corrector of its order-2 steps: the same
// history predicts (its polynomial through the last three points), the corrector is
// q'(t+h) = 2/h (q(t+h) - q(t)) - q'(t), and the predictor's miss, which is
// (1/12 + psi1 psi2 / (6 h^2)) h^3 q''', gives the local error h^3 q''' / 12 (Milne's device).
#include "padae/integrator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <span>

#include "padae/damped_newton.hpp"
#include "padae/dense_output.hpp"
#include "padae/error_noise.hpp"
#include "padae/newton_matrix.hpp"
#include "padae/norms.hpp"
#include "padae/reinitialization.hpp"
#include "padae/root_finder.hpp"
#include "padae/row_refinement.hpp"
#include "padae/subnormals.hpp"
#include "padae/text.hpp"

namespace padae {

namespace {

constexpr int kMaxOrder = 5;
constexpr int kHistory = kMaxOrder + 2;
constexpr int kMaxNewtonIterations = 4;
// Exponential device equations (junctions) far from their solution need many damped Newton
// steps (damped_newton.hpp); tried when modified Newton fails with a fresh matrix, before the
// step is cut.
constexpr int kMaxFullNewtonIterations = 30;
constexpr double kNewtonTolerance = 0.33;   // of the error-test tolerance (IDA's epcon)
constexpr double kMaxConvergenceRate = 0.9;
constexpr int kMaxErrorTestFailures = 10;
constexpr int kMaxNewtonFailures = 10;
// Consecutive steps accepted at the time resolution with their error test failed (see step()).
constexpr int kMaxUnresolvedSteps = 10000;
// A first attempt whose modified Newton diverges on a fresh matrix while its iterates move the
// charges ever further from the predictor, already this many times as far as the error test
// allows, fails the test from its last iterate, without damped Newton (Integrator::Impl::step).
constexpr double kDivergedPastErrorTest = 2;
constexpr int kStepsBetweenJacobians = 20;
constexpr double kJacobianCjChange = 0.25;  // refactor when cj moved by more than this fraction
// A step's modified Newton that took this many corrections converged barely or not at all: its
// matrix is far from the solution's (a junction turning off moves its conductance a decade per
// step), and the next attempt refactors rather than spend as many again on it (IDA, too, refreshes
// its matrix after a slow convergence).
constexpr int kSlowNewtonIterations = 3;
// Convergence on a held matrix is confirmed on it only while it is nowhere twice as stiff as the
// matrix at the solution (NewtonMatrix::drift): on a stiffer matrix a large residual gives a
// small correction (a junction the matrix was factored at in hard conduction, and now nearly
// off, hides amps of residual). Past that, the matrix is refactored at the solution.
constexpr double kConfirmingDrift = 1;
// Nor along the correction it confirms with (NewtonMatrix::kept_mismatch at half the correction
// is a matrix twice as stiff along it): boost.cir at rtol 1e-2 ramped its inductor's current to
// -92 mA through its blocked diode on a matrix the drift kept.
constexpr double kConfirmingMismatch = 0.5;
// The first step after a restart is sized so that backward Euler's local error h^2 q''/2 would be
// half the tolerance (IDA's target), the first step's error test being backward Euler's.
constexpr double kRestartCurvatureBound = 1;
// The start-up after a restart raises the order with each step up to this one. The trapezoidal
// start leaves a history exact to order 2 (the Hermite quadratic through a virtual point): the
// higher divided differences are more the virtual point's than the solution's, and so are the
// estimates made from them (buck converter: order-4 start-up steps failed the error test by up to
// 19x, about ten times what the order-3 step's estimate of order 4 predicted). The order rises
// further once real points fill the history (IDA's order selection, after k + 1 steps of one size).
constexpr int kStartupOrder = 3;
// Source corners one step may pass (guards sampled at each): bounds a step's work.
constexpr int kMostCornersPassed = 1000;
constexpr double kEps = std::numeric_limits<double>::epsilon();
// An unknown this large is on its way out of double's range (max 1.8e308).
constexpr double kOverflowing = 1e300;
// Zeno behaviour: this many consecutive event intervals, each shrinking by this ratio or more,
// are taken as events accumulating toward a finite time.
constexpr int kAccumulationEvents = 12;
constexpr double kAccumulationRatio = 0.8;
// The solution inside a step: the largest c, relative to the step's own, and the continuation's
// first point, at 2^-kContinuationHalvings of the distance from the step's start.
constexpr double kMaxStiffening = 1e3;
constexpr int kContinuationHalvings = 10;

// Over the entries that have a weight (the others are not tested).
double weighted_norm(const Vector& v, const Vector& inverse_weight, ErrorNorm kind) {
  if (kind == ErrorNorm::max) return weighted_max_norm(v, inverse_weight);
  double sum = 0;
  int count = 0;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (inverse_weight[i] == 0) continue;
    double scaled = v[i] * inverse_weight[i];
    sum += scaled * scaled;
    ++count;
  }
  return count > 0 ? std::sqrt(sum / count) : 0.0;
}

// IDA's: an error estimate, in tolerances, is taken to be at least this much (it says nothing
// finer).
constexpr double kErrorResolution = 1e-4;

// IDA's step ratio: the step that brings a local error estimate of order error_order to half
// the tolerance, relative to the one that made it.
double step_ratio(double error_estimate, int error_order) {
  return std::pow(2 * error_estimate + kErrorResolution, -1.0 / (error_order + 1));
}

// The error estimate's round-off relative to an unknown's peak: at order 5 the estimate is a
// sixth difference of q, up to 2^6 times the few units of round-off in each value, and these are
// units of the circuit's magnitudes, not of a node's value as it crosses zero (the relaxation
// oscillator at reltol 2e-12, vntol 1e-16 failed the error test where v(cap) crosses zero:
// 3.3 tolerances at h = 4.7e-6 s, 1.2 at 8.4e-7 s).
constexpr double kEstimateRoundoff = 256 * kEps;

// The options as the integrator uses them: the orders its method has, rtol at least
// kSmallestRtol, and a peak floor (if any) at least the estimate's round-off.
Options within_limits(Options options) {
  options.max_order = std::clamp(options.max_order, 1, options.method == Method::trapezoidal ? 2 : kMaxOrder);
  options.rtol = std::max(options.rtol, kSmallestRtol);
  if (options.peak_floor > 0) options.peak_floor = std::max(options.peak_floor, kEstimateRoundoff / options.rtol);
  return options;
}

}  // namespace

struct Integrator::Impl {
  Impl(System& system_in, Options options_in);

  // --- steps -----------------------------------------------------------------------------
  StepOutcome step(double t_stop);
  void set_coefficients();
  void predict();
  enum class Newton { modified, modified_fresh, full };
  NewtonOutcome correct(double t_new, Newton mode);
  void hold_matrix();
  int sign_on_branch(double t_new);
  void newton_correction(const CorrectorEquation& equation);
  void track_iterate_error();
  bool diverged_past_error_test() const;
  // The error the test measured, in tolerances, into `error`; error_k and error_k_minus_1 are
  // the estimates at orders k and k - 1 that choose the next order.
  bool error_test(double& error, double& error_k, double& error_k_minus_1, int& order_new);
  bool kink_crossed() const;
  bool kink_spoils_derivative();
  // The first step after a (re)start is the trapezoidal rule from the re-initialization's q'
  // (unless the order is held at 1, or a fast mode is left to the integration); its error is
  // tested as backward Euler's, the only estimate one point allows, which bounds the
  // trapezoidal rule's.
  bool trapezoidal_start() const { return order_used == 0 && options.max_order >= 2 && !fast_mode_left; }
  bool trapezoidal_method_step() const { return options.method == Method::trapezoidal && order == 2; }
  bool trapezoidal_step() const { return trapezoidal_method_step() || trapezoidal_start(); }
  void complete_step(double error_k, double error_k_minus_1, int order_new);
  void choose_step(double error_estimate, int error_order, double h_max, double error_growth);
  double error_growth(double error_k) const;
  void restore();
  void rescale_first_step();
  void update_weights();
  double minimum_step() const;
  bool continues_last_change() const;

  // The last step's interpolating polynomial of x or of q at t_at, or its derivative there.
  enum class Interpolated { value, derivative };
  enum class Quantity { x, q };
  Vector interpolate(double t_at, Interpolated what = Interpolated::value, Quantity of = Quantity::x) const;
  // The same into out (sized n): no allocation, for the per-step screening of the guards.
  void interpolate(double t_at, Vector& out, Interpolated what = Interpolated::value, Quantity of = Quantity::x) const;
  // The value of x's polynomial for the listed unknowns only, into out (sized n).
  void interpolate(double t_at, std::span<const int> unknowns, Vector& out) const;
  double first_step_estimate(double t_at, const Vector& x_at);
  // x at t_at inside the last step as a step of its order from its start would reach it
  // (dense_output.hpp); empty where Newton finds no solution.
  // Newton starts from guess if given.
  std::optional<Vector> step_solution(DenseOutput& solver, double t_at, const Vector* guess = nullptr) const;
  // step_solution(), or the polynomial's x counted in statistics.unsolved_points.
  Vector solution_or_polynomial(DenseOutput& solver, Statistics& counted_in, double t_at) const;
  // Where an output row at t_at inside the last step comes from, for these unknowns. The error
  // test controls the charges, and so the unknowns that are functions of one charge each: the
  // polynomial serves for them. Any other unknown (an algebraic one, or one in a hidden
  // algebraic direction such as a floating capacitor's common mode) comes from the polynomial
  // where the step vouches for it (step_vouches_for_polynomial), or where checks certify it,
  // or from step_solution interpolated where checks certify that (row_refinement.hpp), else
  // it is solved. A source corner the step passed reaches only the unknowns of its own block
  // of the pattern, all algebraic (corner_can_reach), which bend there where no interpolant
  // can: they are solved.
  RowRefinement::Row row_source(double t_at, std::span<const int> unknowns);
  bool charges_determine(std::span<const int> unknowns);
  // Whether the last step, without a restart after it, vouches for its polynomial at the listed
  // unknowns, so that the checks need not.
  bool step_vouches_for_polynomial(std::span<const int> unknowns);
  // The accepted step whose polynomial interpolate() and step_solution() use: previous_step
  // after a restart, else the current history's (its end may be another step's end too: both
  // steps of a restart inside a step can end on the same corner).
  struct StepView {
    double anchor;  // the step's end
    int order;
    const std::array<Vector, kHistory>& phi_x;
    const std::array<Vector, kHistory>& phi_q;
    const std::array<double, kHistory>& psi;
    const Predicates& p;  // the mode the step was taken in
    long number;          // counted in statistics.steps
    bool corner_inside;   // the step passed a source corner
  };
  StepView last_step() const;
  // solution_or_polynomial() for the guards (events, passed corners), remembered for the output
  // rows at the same instants.
  Vector located_solution(double t_at);
  const Vector* remembered_solution(double t_at) const;

  // --- events ----------------------------------------------------------------------------
  bool evaluate_guards(double t_at, const Vector& x_at, Vector& out) const;
  bool crossed(const Vector& guards) const;
  // A guard that crosses and crosses back between two instants of the last step where none is
  // crossed: the earliest instant found where one is, with the guards there; nullopt if none.
  struct GuardSample {
    double t;
    Vector guards;
  };
  std::optional<GuardSample> crossing_inside(double t_left, const Vector& guards_left, double t_right,
                                             const Vector& guards_right);
  // The guards on the solution at t_at, if one is crossed there.
  std::optional<GuardSample> confirmed_crossing(double t_at);
  Vector screened_guards, screened_state;  // scratch of crossing_inside()
  std::vector<double> screened_times;      // scratch of crossing_inside()
  DenseOutput& locator();
  StepOutcome handle_state_event(double t_left, const Vector& guards_left, double t_right,
                                 const Vector& guards_right);
  bool settle(double t_at, const Vector& x_start, const Predicates& target,
              bool record_flips);
  Predicates undetermined_flipped(double t_at, const Vector& x_at, const Predicates& mode, double cj,
                                  const std::vector<char>& kept);
  void restart(double t_at, const ConsistentState& consistent);
  // The system's charges measured from (x_at, p) (System::measure_charges_from), the ones held
  // shifted to match.
  void measure_charges_from(double t_at, const Vector& x_at);

  StepOutcome fail(double t_at, std::string reason, int unknown = -1, std::string diagnosis = {}) {
    failure = Failure{t_at, std::move(reason), unknown, std::move(diagnosis)};
    return {StepKind::failed, t_at};
  }

  System& system;
  Options options;
  const int n;
  const int predicate_count;
  const int kink_count;
  Statistics statistics;
  Vector absolute_tolerance;
  // absolute_tolerance raised to the round-off of each unknown's magnitude (kEstimateRoundoff of
  // its peak so far), updated with the weights: no Newton iteration (steps, events, rows) asks
  // for less than double precision resolves (vntol 1e-15 V on a 12 V bridge stalled Newton near
  // a node's zero crossing).
  Vector resolvable_tolerance;
  NewtonMatrix newton;
  Reinitializer reinitializer;
  // Solutions inside a step, made on first use: one locates events (its work counts as the
  // integration's), one writes output with counters of its own (writing output never changes
  // the integration: neither its kept factorization nor its statistics).
  std::unique_ptr<DenseOutput> location_solver, output_solver;
  Statistics output_statistics;
  Vector output_row;  // dense_output()'s for the listed unknowns
  std::vector<int> every_unknown;  // 0 ... n - 1, what dense_output(t) asks for
  DenseOutput& writer();
  // Of the last step's rows (row_source).
  RowRefinement output_refinement{[this](double t_of, Vector& out) { interpolate(t_of, out); },
                                  [this](double t_of, const Vector& guess) { return step_solution(writer(), t_of, &guess); }};
  // What row_source() found for the rows of step number `step` and this list of unknowns:
  // judged once per step, not per row.
  struct RowPlan {
    long step = -1;
    std::vector<int> unknowns;
    bool polynomial = false;  // charges_determine() or step_vouches_for_polynomial()
  } row_plan;
  Vector error_response;  // step_vouches_for_polynomial()'s
  // NewtonMatrix::charge_determined in mode `mode` (a mode may switch charges in or out).
  struct ChargeDetermined {
    Predicates mode;
    std::vector<char> unknowns;
  } charge_determined;
  // The located solutions in accepted step number located_step.
  struct Located {
    double t;
    Vector x;
  };
  std::vector<Located> located;
  long located_step = -1;

  // The solution.
  double t = 0;
  Vector x;
  Predicates p;
  Predicates step_predicates;  // p during the current step (an event inside it changes p)
  Vector guards_now;  // guards at (t, x)
  Vector kinks_now, kinks_new;  // System::kinks at (t, x), and at the attempt's x_new
  Vector algebraic_indicator;   // 1 on algebraic unknowns, 0 on the others
  Vector kink_response, kink_weight;  // kink_spoils_derivative()'s
  // A step retaken at order 1 after a kink: Newton starts from the attempt's solution.
  bool retaking_at_kink = false;
  // Accepted steps since the last that crossed a kink (kMaxOrder after a restart): a formula
  // whose history reached back across it would overshoot the kink as the retaken step's would.
  int steps_past_kink = kMaxOrder;
  Vector retake_start;
  double next_time_event = std::numeric_limits<double>::infinity();  // the first corner after t
  // Per row: whether a corner in its forcing can bend the solution, i.e. the row shares a block
  // of the pattern with a differential unknown. A step ends on such a corner and passes the
  // others, whose sources only reach algebraic unknowns (exact at any instant).
  std::vector<char> row_bends_solution;
  // Per unknown: whether it is in such a block without a differential unknown, the only
  // unknowns a passed corner reaches (the blocks decouple).
  std::vector<char> corner_can_reach;
  std::vector<int> corner_rows;
  bool corner_bends(double t_from);
  struct CornersAhead {
    double bending, last_passable;
  };
  CornersAhead corners_ahead(double t_limit);
  EventRecord last_event;
  Failure failure{0, "", -1};
  double last_event_time = -std::numeric_limits<double>::infinity();
  double last_event_interval = std::numeric_limits<double>::infinity();
  int events_in_burst = 0;      // consecutive events within the time resolution
  int shrinking_intervals = 0;  // consecutive event intervals shrinking geometrically

  // BDF history: modified divided differences of x and of q.
  std::array<Vector, kHistory> phi_x, phi_q;
  std::array<double, kHistory> psi{}, alpha{}, beta{}, sigma{}, gamma{};
  double anchor = 0;  // the time phi_x[0] belongs to
  // The last step's interpolating polynomials, kept across a restart: output inside a step that
  // ended at an event or a source corner is still interpolated.
  struct Polynomial {
    double anchor = 0;
    int order = 0;
    std::array<Vector, kHistory> phi_x, phi_q;
    std::array<double, kHistory> psi{};
    Predicates p;  // the mode the step was taken in
    long number = 0;  // counted in statistics.steps
    bool corner_inside = false;  // the step passed a source corner
  } previous_step;
  bool corner_inside = false;  // the last step passed a source corner
  bool after_restart() const { return order_used == 0 && previous_step.order > 0; }
  // The weights of the polynomial sum_j w_j phi_j (its value or derivative at t_at) of a step
  // that ended at anchor_at; w_j = 0 above the order.
  static std::array<double, kHistory> polynomial_weights(double anchor_at, int order_of,
                                                         const std::array<double, kHistory>& psi_of, double t_at,
                                                         Interpolated what);
  int order = 1, order_used = 0, constant_steps = 0;
  bool virtual_point_in_history = false;  // the trapezoidal start's (complete_step)
  bool startup_phase = true;
  // The restart's state leaves a mode faster than the re-initialization's steps to the
  // integration: the trapezoidal rule would flip its sign step by step (a 1e-17 s RL, an ideal
  // diode's ROFF against its inductor, swung v(sw) from -18 V to +18 V), backward Euler damps it.
  bool fast_mode_left = false;
  std::optional<UnresolvedTransient> unresolved;
  int unresolved_in_a_row = 0;
  double h = 0, h_used = 0, cj = 0, error_coefficient = 0;
  // The step the error control chose for the last step, before it was shortened to end on a
  // source corner or a stop: a restart there starts from it (the shortened step says nothing
  // about the motion).
  double h_planned = 0;
  // The last accepted step's estimate at its order (0: none since the last restart), for the
  // predictive step control (error_growth()).
  struct AcceptedError {
    int order = 0;
    double error = 0, h = 0, growth = 1;
  } last_accepted;
  Vector q_derivative;  // q' at t, as the last corrector (or the restart) gave it: the trapezoidal history

  // Newton matrix bookkeeping (modified Newton with reuse).
  bool have_matrix = false;
  double cj_of_matrix = 0;
  long step_of_matrix = 0;
  double convergence_factor = kUnmeasuredConvergenceFactor;
  bool newton_was_slow = false;  // the last attempt's modified Newton (kSlowNewtonIterations)

  Vector inverse_weight_x, inverse_weight_q, charge_weight, charge_tolerance;
  Vector peak_magnitude, error_scale;  // largest |x| so far; the magnitude rtol applies to
  Vector x_predicted, q_predicted, q_derivative_predicted, x_new, q_new, delta, residual;
  Vector next_iterate;  // where correct()'s confirming correction would take x_new
  double newton_start_fraction = 1;  // how far toward x_predicted Newton starts (predict())
  Vector correction_x, correction_q;
  Vector previous_correction_x;  // the step before's correction_x (step_vouches_for_polynomial)
  long steps_at_restart = 0;     // statistics.steps at the last restart
  // From the start of a run until a step is as long: the step the motion's curvature alone
  // allows, tried once should Newton fail on IDA's shorter steps (restart()).
  double first_step_by_curvature = 0;
  Vector kept_mismatch;  // correct()'s scratch
  // The error test's estimate at modified Newton's last iterate, and at the one before it.
  double iterate_error = 0, previous_iterate_error = 0;
  Vector iterate_charge_move;
};

Integrator::Impl::Impl(System& system_in, Options options_in)
    : system(system_in),
      options(within_limits(options_in)),
      n(system_in.size()),
      predicate_count(system_in.predicate_count()),
      kink_count(system_in.kink_count()),
      absolute_tolerance(Vector::NullaryExpr(system_in.size(),
                                             [&](Eigen::Index i) {
                                               return system_in.absolute_tolerance(
                                                   static_cast<int>(i), options_in.atol);
                                             })),
      resolvable_tolerance(absolute_tolerance),
      newton(system_in, statistics, absolute_tolerance / options.rtol),
      reinitializer(system_in, newton, statistics, options, resolvable_tolerance, peak_magnitude) {
  every_unknown.resize(n);
  peak_magnitude.setZero(n);
  kinks_now.setZero(kink_count);
  kinks_new.setZero(kink_count);
  algebraic_indicator = Vector::NullaryExpr(n, [&](Eigen::Index i) {
    return system_in.kind(static_cast<int>(i)) == UnknownKind::algebraic ? 1.0 : 0.0;
  });
  std::iota(every_unknown.begin(), every_unknown.end(), 0);
  for (auto& v : phi_x) v.setZero(n);
  for (auto& v : phi_q) v.setZero(n);

  // The blocks of the pattern: rows (0 .. n-1) and columns (n .. 2n-1) joined by every entry.
  std::vector<int> parent(2 * static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  const Pattern& pattern = system.pattern();
  for (int column = 0; column < n; ++column)
    for (int k = pattern.column_starts()[column]; k < pattern.column_starts()[column + 1]; ++k)
      parent[root(pattern.row_indices()[k])] = root(n + column);
  std::vector<char> block_is_dynamic(parent.size(), 0);
  for (int column = 0; column < n; ++column)
    if (system.kind(column) == UnknownKind::differential) block_is_dynamic[root(n + column)] = 1;
  row_bends_solution.resize(n);
  for (int row = 0; row < n; ++row) row_bends_solution[row] = block_is_dynamic[root(row)];
  corner_can_reach.resize(n);
  for (int column = 0; column < n; ++column) corner_can_reach[column] = !block_is_dynamic[root(n + column)];
}

// Whether the corner next_time_event(t_from) can bend the solution (if unsure, it can).
bool Integrator::Impl::corner_bends(double t_from) {
  corner_rows.clear();
  if (!system.time_event_rows(t_from, corner_rows)) return true;
  return std::any_of(corner_rows.begin(), corner_rows.end(), [&](int row) { return row_bends_solution[row] != 0; });
}

// The corners ahead of a step up to t_limit: the first that bends the solution (the step ends
// there and the BDF restarts), or else the kMostCornersPassed-th, beyond which the step may not
// go: it samples the guards at each corner it passes, and a step over astronomically many (a
// clock far faster than the circuit) would not end. +inf where there is none.
Integrator::Impl::CornersAhead Integrator::Impl::corners_ahead(double t_limit) {
  int passed = 0;
  for (double from = t, corner = next_time_event; corner <= t_limit; from = corner, corner = system.next_time_event(corner)) {
    if (corner_bends(from)) return {corner, std::numeric_limits<double>::infinity()};
    if (++passed == kMostCornersPassed) return {std::numeric_limits<double>::infinity(), corner};
  }
  return {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
}

double Integrator::Impl::minimum_step() const { return std::max(options.min_step, time_resolution(t, options)); }

void Integrator::Impl::update_weights() {
  peak_magnitude = peak_magnitude.cwiseMax(x.cwiseAbs());
  resolvable_tolerance = absolute_tolerance + kEstimateRoundoff * peak_magnitude;
  inverse_weight_x = (options.rtol * x.cwiseAbs() + resolvable_tolerance).cwiseInverse();
  // The error is tested on the dynamic rows' q, in the units of x: a row's tolerance is the
  // charge its unknowns' tolerances represent (for q_i = x_i, IDA's rtol |x_i| + atol_i).
  error_scale = padae::error_scale(x, peak_magnitude, options.peak_floor);
  charge_tolerance = options.rtol * error_scale + absolute_tolerance;
  // The state at t is defined only to the rounding of t: an unknown moving at x' is uncertain by
  // |x'| eps |t|, which no step resolves (a switch onto a 0.7 ps RC at t = 2 ms moves 1e13 V/s,
  // 4e-6 V per ulp of t, where rtol 1e-8 asked for 7e-11 V). phi_x[1] = h x', at a restart with
  // the first step's h.
  const double h_of_history = h_used > 0 ? h_used : h;
  if (h_of_history > 0) charge_tolerance += (kEps * std::abs(t) / h_of_history) * phi_x[1].cwiseAbs();
  newton.charge_scale(charge_tolerance, charge_weight);
  // At a restart x' is the look-ahead's chord over its settling step, for the prediction: it
  // lags a fast mode the event starts (a switch opening 2.5 A of 1 mH into 1 TOhm at t = 1 ms,
  // 2.5e15 A/s, seen 64 times slower; every step failed the error test at the time
  // resolution), so q' = -f after the event, exact, counts too.
  if (h_used == 0 && h > 0)
    for (int i = 0; i < n; ++i)
      if (charge_weight[i] > 0) charge_weight[i] += (kEps * std::abs(t) / h) * std::abs(phi_q[1][i]);
  inverse_weight_q.resize(n);
  for (int i = 0; i < n; ++i)
    inverse_weight_q[i] = charge_weight[i] > 0 ? 1.0 / charge_weight[i] : 0.0;
}

// IDA's IDASetCoeffs: the coefficients of the variable-step formula for (h, order), and the
// scaling of the divided differences phi -> phi*.
void Integrator::Impl::set_coefficients() {
  if (h != h_used || order != order_used) constant_steps = 0;
  constant_steps = std::min(constant_steps + 1, order_used + 2);
  if (order + 1 >= constant_steps) {
    beta[0] = alpha[0] = sigma[0] = 1;
    gamma[0] = 0;
    double span = h;
    for (int i = 1; i <= order; ++i) {
      double previous = psi[i - 1];
      psi[i - 1] = span;
      beta[i] = beta[i - 1] * psi[i - 1] / previous;
      span = previous + h;
      alpha[i] = h / span;
      sigma[i] = i * sigma[i - 1] * alpha[i];
      gamma[i] = gamma[i - 1] + alpha[i - 1] / h;
    }
    psi[order] = span;
  }
  double alpha_s = 0, alpha_0 = 0;
  for (int i = 0; i < order; ++i) {
    alpha_s -= 1.0 / (i + 1);
    alpha_0 -= alpha[i];
  }
  cj = -alpha_s / h;
  error_coefficient = std::max(std::abs(alpha[order] + alpha_s - alpha_0), alpha[order]);
  if (trapezoidal_step()) cj = 2 / h;
  // The predictor misses by (1/12 + prod / (6 h^3)) h^3 q''', prod the product of t + h - t_j
  // over the points t_j it interpolates: t, t - psi0, t - psi1 (Hermite's after the start: t
  // twice and t - psi0).
  if (trapezoidal_method_step())
    error_coefficient = h * h / (h * h + 2 * (virtual_point_in_history ? psi[0] : psi[2]) * psi[1]);
  for (int i = constant_steps; i <= order; ++i) {
    phi_x[i] *= beta[i];
    phi_q[i] *= beta[i];
  }
}

void Integrator::Impl::restore() {
  for (int j = 1; j <= order; ++j) psi[j - 1] = psi[j] - h;
  for (int j = constant_steps; j <= order; ++j) {
    phi_x[j] /= beta[j];
    phi_q[j] /= beta[j];
  }
}

// Whether the attempt's change of the charges goes the way the last step's went (at a restart:
// the way the initial derivative points), in the error test's weights.
bool Integrator::Impl::continues_last_change() const {
  return ((q_new - phi_q[0]).cwiseProduct(inverse_weight_q).dot(phi_q[1].cwiseProduct(inverse_weight_q))) > 0;
}

// In the first step after a (re)start there is no previous step: the history is the initial
// derivative times h, so it follows every change of h (IDA's IDAHandleNFlag for nst == 0).
void Integrator::Impl::rescale_first_step() {
  if (order_used != 0 || h == psi[0]) return;
  const double ratio = h / psi[0];
  phi_x[1] *= ratio;
  phi_q[1] *= ratio;
  psi[0] = h;
}

void Integrator::Impl::predict() {
  x_predicted = phi_x[0];
  q_predicted = phi_q[0];
  q_derivative_predicted.setZero(n);
  for (int j = 1; j <= order; ++j) {
    x_predicted += phi_x[j];
    q_predicted += phi_q[j];
    q_derivative_predicted += gamma[j] * phi_q[j];
  }
  // The corrector's q' = q'_pred + cj (q - q_pred) is then the trapezoidal one.
  if (trapezoidal_step()) q_derivative_predicted = cj * (q_predicted - phi_q[0]) - q_derivative;
  // Newton starts at the predictor, or short of it where the model limits the move from the
  // step's start: an extrapolated junction voltage far into forward bias would be crept back
  // one n VT per iteration. The error test still measures from the predictor itself.
  newton_start_fraction = newton.step_fraction(x, x_predicted);
}

// Newton on  qdot_pred + cj (q(x) - q_pred) + f(t, x) = 0, from x_pred or short of it
// (predict()): modified Newton with the matrix reused across steps (IDA's), or damped Newton
// refactored at every iterate (mode full).
NewtonOutcome Integrator::Impl::correct(double t_new, Newton mode) {
  iterate_error = previous_iterate_error = 0;
  if (retaking_at_kink) x_new = retake_start;
  else if (newton_start_fraction < 1) x_new = x + newton_start_fraction * (x_predicted - x);
  else x_new = x_predicted;
  const CorrectorEquation equation{t_new, cj, q_predicted, q_derivative_predicted, x_predicted, p};
  if (mode == Newton::full) {
    const NewtonOutcome outcome = solve_damped(newton, statistics, equation, inverse_weight_x, kNewtonTolerance, options.rtol,
                                               kMaxFullNewtonIterations, x_new, sign_on_branch(t_new));
    hold_matrix();
    have_matrix = outcome != NewtonOutcome::singular;
    if (outcome == NewtonOutcome::converged) q_new = newton.load().q;
    return outcome;
  }
  // A predictor outside the model's domain (a source that touches 0 under a sqrt, extrapolated
  // below it) is no reason to cut the step: Newton starts from the step's start instead.
  if (mode == Newton::modified_fresh) {
    auto factored = newton.factor(t_new, x_new, p, cj);
    if (factored == NewtonMatrix::Outcome::outside_domain) factored = newton.factor(t_new, x_new = x, p, cj);
    if (factored == NewtonMatrix::Outcome::outside_domain) return NewtonOutcome::outside_domain;
    if (factored == NewtonMatrix::Outcome::singular) return NewtonOutcome::singular;
    hold_matrix();
  } else if (newton.evaluate(t_new, x_new, p) != EvalStatus::ok && newton.evaluate(t_new, x_new = x, p) != EvalStatus::ok) {
    return NewtonOutcome::outside_domain;
  }

  const double toldel = 1e-4 * kNewtonTolerance;
  // Affine equations on their exact matrix: what contraction is left there is the rounding's, and
  // no other matrix would judge convergence better.
  const bool exact_matrix = newton.factored_exactly(p, cj);
  double first_norm = 0;
  for (int m = 0, m_first = 0;; ++m) {
    ++statistics.newton_iterations;
    newton_correction(equation);
    x_new -= delta;
    // Converged means every unknown within its tolerance, as circuit simulators require: an
    // algebraic current that steers a switch must not hide in an average.
    double norm = weighted_max_norm(delta, inverse_weight_x);
    if (!std::isfinite(norm)) return NewtonOutcome::diverged;
    bool converged = false;
    if (m == m_first) {
      first_norm = norm;
      converged = norm <= 1e-4 * toldel || convergence_factor * norm <= kNewtonTolerance;
    } else {
      double rate = std::pow(norm / first_norm, 1.0 / (m - m_first));
      if (rate > kMaxConvergenceRate) return NewtonOutcome::diverged;
      convergence_factor = rate / (1 - rate);
      converged = convergence_factor * norm <= kNewtonTolerance;
    }
    if (!converged && m + 1 >= kMaxNewtonIterations) return NewtonOutcome::diverged;
    if (!converged || exact_matrix) {
      // q at the new point, which the history needs exactly (charge conservation).
      if (newton.evaluate(t_new, x_new, p) != EvalStatus::ok) return NewtonOutcome::outside_domain;
      if (converged) break;  // on the exact matrix: no confirming correction
      if (mode == Newton::modified_fresh) track_iterate_error();  // what step() asks of a divergence
      continue;
    }
    // A convergence judged from a remembered rate must really hold: the next correction, on a
    // matrix that can judge it, must be within the tolerance too (a junction turning off inside
    // the step breaks the linearization an earlier step's rate was measured on), and so must the
    // model's nonlinear currents along it (System::currents_converged: a node within its
    // tolerance can be many N VT from a junction's solution). A matrix that far from the one held
    // may be across a fold from the step's start (damped_newton.hpp): such a solution is refused.
    auto confirming = newton.factor(t_new, x_new, p, cj, kConfirmingDrift);
    // The correction the matrix at x_new would make is at most `amplification` times delta.
    double amplification = 1;
    bool settled = false;  // currents_settled() held for this delta
    const auto currents_settled = [&] {
      next_iterate = x_new - amplification * delta;
      return newton.currents_converged(x_new, next_iterate, options.rtol);
    };
    if (confirming == NewtonMatrix::Outcome::kept) {
      newton_correction(equation);
      // Row by row the held matrix can look close where it is far along the correction
      // (NewtonMatrix::kept_mismatch). Along it, the correction the matrix at the solution would
      // make is at most correction / (1 - ratio), ratio = mismatch / correction (the Neumann
      // series): the held matrix confirms where it is not twice as stiff along the correction or
      // where that bound is within the tolerance. Compared at its own cj: a constant Jacobian's
      // held matrix is then the matrix at the solution.
      if (!system.constant_jacobian()) {
        newton.kept_mismatch(delta, cj_of_matrix, kept_mismatch);
        const double correction = weighted_max_norm(delta, inverse_weight_x);
        const double ratio = correction > 0 ? weighted_max_norm(kept_mismatch, inverse_weight_x) / correction : 0;
        amplification = ratio < 1 ? 1 / (1 - ratio) : std::numeric_limits<double>::infinity();
        const bool held_confirms = ratio < kConfirmingMismatch || correction * amplification <= kNewtonTolerance;
        settled = held_confirms && currents_settled();
        if (!settled) {
          confirming = newton.factor(t_new, x_new, p, cj);
          amplification = 1;
        }
      }
    }
    if (confirming == NewtonMatrix::Outcome::outside_domain) return NewtonOutcome::outside_domain;
    if (confirming == NewtonMatrix::Outcome::singular) return NewtonOutcome::singular;
    if (confirming == NewtonMatrix::Outcome::ok) {
      const int sign = newton.determinant_sign();
      if (sign != sign_on_branch(t_new)) return NewtonOutcome::diverged;
      // sign_on_branch() factored the matrix at the step's start and loaded f and q there: the
      // matrix at the solution is factored again, for the correction and for q_new.
      if (newton.factor(t_new, x_new, p, cj) != NewtonMatrix::Outcome::ok) return NewtonOutcome::singular;
      hold_matrix();
      newton_correction(equation);
    }
    if (weighted_max_norm(delta, inverse_weight_x) <= kNewtonTolerance && (settled || currents_settled())) break;
    convergence_factor = kUnmeasuredConvergenceFactor;
    if (m + 1 >= kMaxNewtonIterations) return NewtonOutcome::diverged;
    // The rate is measured afresh from the next correction on: it may be on another matrix.
    m_first = m + 1;
  }
  q_new = newton.load().q;
  return NewtonOutcome::converged;
}

// The error test's estimate were Newton to stop at x_new (whose q was just evaluated).
void Integrator::Impl::track_iterate_error() {
  iterate_charge_move = newton.load().q - q_predicted;
  previous_iterate_error = iterate_error;
  iterate_error = error_coefficient * weighted_norm(iterate_charge_move, inverse_weight_q, options.norm);
}

// Where modified Newton diverged with its iterates heading ever further from the predictor, and
// already past the error test's bound, damped Newton converges only for the error test to reject
// the step: on boost.cir, where the steps approach the output diode's turn-off, 224 of the 271
// attempts that needed damped Newton failed the test. The iterates' estimates fall short of the
// solution's there (54 against 360, 7 against 139); of the attempts that passed (boost, buck and
// bridge rectifier at rtol 1e-3 and 1e-5), none had estimates growing past 2.
bool Integrator::Impl::diverged_past_error_test() const {
  return iterate_error > kDivergedPastErrorTest && iterate_error > previous_iterate_error;
}

// The sign of det J at the step's start (x, on the branch the step follows) with this step's cj;
// 0 when J is singular there. The matrix factored there becomes the one held.
int Integrator::Impl::sign_on_branch(double t_new) {
  if (newton.factor(t_new, x, p, cj) != NewtonMatrix::Outcome::ok) {
    have_matrix = false;
    return 0;
  }
  hold_matrix();
  return newton.determinant_sign();
}

// The matrix just factored (at this step's cj) is the one modified Newton goes on with.
void Integrator::Impl::hold_matrix() {
  have_matrix = true;
  cj_of_matrix = cj;
  step_of_matrix = statistics.steps;
  convergence_factor = kUnmeasuredConvergenceFactor;
}

// delta = J^-1 r(x_new), r the corrector's residual at the last evaluation (which was at x_new).
void Integrator::Impl::newton_correction(const CorrectorEquation& equation) {
  corrector_correction(newton, equation, x_new, residual, delta);
  const double cj_ratio = cj / cj_of_matrix;
  if (cj_ratio != 1.0) delta *= 2.0 / (1.0 + cj_ratio);  // compensates the stale cj
}

// IDA's IDATestError: local error at order k from the q correction, and the estimates at orders
// k-1 and k-2 that decide whether to lower the order.
bool Integrator::Impl::error_test(double& error, double& error_k, double& error_k_minus_1, int& order_new) {
  correction_q = q_new - q_predicted;
  double norm_k = weighted_norm(correction_q, inverse_weight_q, options.norm);
  order_new = order;
  error_k_minus_1 = 0;
  error = error_coefficient * norm_k;
  if (trapezoidal_method_step()) {
    error_k = error;
    return error <= 1.0;
  }
  error_k = sigma[order] * norm_k;
  double terr_k = (order + 1) * error_k;
  if (order > 1) {
    Vector lower = phi_q[order] + correction_q;
    error_k_minus_1 = sigma[order - 1] * weighted_norm(lower, inverse_weight_q, options.norm);
    double terr_k_minus_1 = order * error_k_minus_1;
    if (order > 2) {
      lower += phi_q[order - 1];
      double terr_k_minus_2 = (order - 1) * sigma[order - 2] * weighted_norm(lower, inverse_weight_q, options.norm);
      if (std::max(terr_k_minus_1, terr_k_minus_2) <= terr_k) order_new = order - 1;
    } else if (terr_k_minus_1 <= 0.5 * terr_k) {
      order_new = order - 1;
    }
  }
  return error <= 1.0;
}

// Whether the step crossed a kink (System::kinks) with a formula of order > 1 and so put an
// algebraic unknown off by more than its tolerance. Off by: the formula's derivative defect,
// cj times the local error estimate of q, through the Newton matrix (the stiff components'
// estimate of Hairer and Wanner); an unknown a stiff mode ties to a derivative takes it in full.
// Held to rtol of the unknown's peak so far: an error seen against the waveform it belongs to.
// The error test leaves algebraic unknowns alone (SPICE's: charges and fluxes only), and an
// inductor's current within its tolerance says nothing of L di/dt where the kink is: boost.cir's
// switch node, held by ROFF alone once the diode blocks, fell to -0.86 V (Vin = 5 V). Called on
// every attempt the error test passed; leaves kinks_new at x_new (kinks_now once accepted).
bool Integrator::Impl::kink_spoils_derivative() {
  if (kink_count == 0) return false;
  system.kinks(x_new, kinks_new);
  // Order k's formula reaches back to the point k - 1 steps before the step's start.
  const bool spans_kink = kink_crossed() || steps_past_kink < order - 1;
  if (order == 1 || trapezoidal_step() || !spans_kink) return false;
  kink_response = (cj * error_coefficient) * correction_q;
  newton.solve(kink_response);
  kink_weight = algebraic_indicator.cwiseQuotient(options.rtol * padae::error_scale(x_new, peak_magnitude, 1.0) +
                                                  absolute_tolerance);
  return weighted_norm(kink_response, kink_weight, options.norm) > 1;
}

// Whether the attempt's x_new lies across a kink from x (kinks_new against kinks_now).
bool Integrator::Impl::kink_crossed() const {
  for (int k = 0; k < kink_count; ++k)
    if ((kinks_new[k] > 0) != (kinks_now[k] > 0)) return true;
  return false;
}

// The next step from the local error estimate of order error_order, and from the growth of the
// error per step that error_growth() predicts.
void Integrator::Impl::choose_step(double error_estimate, int error_order, double h_max, double error_growth) {
  const double ratio = step_ratio(error_estimate * error_growth, error_order);
  if (ratio >= 2) h = std::min(2 * h, h_max);
  else if (ratio <= 1) h *= std::clamp(ratio, 0.5, 0.9);
}

// Gustafsson's predictive control: how much the error constant grew from the last accepted step
// to this one, err_k / err_prev * (h_prev / h)^(k+1), taken to go on growing for the next step;
// 1 where it does not grow, or where the two estimates are not of the same order. Where a
// junction turns off towards zero current its voltage is logarithmic in the current, the
// derivatives grow like 1 / (t* - t)^k, and a step rule that only looks back at the last error
// keeps the step until the error test fails, every second step (boost.cir in discontinuous
// conduction).
double Integrator::Impl::error_growth(double error_k) const {
  if (last_accepted.order != order_used || last_accepted.error <= 0) return 1;
  const double growth = (error_k + kErrorResolution) / (last_accepted.error + kErrorResolution) *
                        std::pow(last_accepted.h / h_used, order_used + 1);
  return std::max(growth, 1.0);
}

// IDA's IDACompleteStep: order and step for the next step, then the divided differences.
void Integrator::Impl::complete_step(double error_k, double error_k_minus_1, int order_new) {
  ++statistics.steps;
  const bool started = trapezoidal_start();
  virtual_point_in_history = false;
  const int order_change = order - order_used;
  order_used = order;
  h_used = h;
  // A growth seen on two steps in a row: a single estimate moves by factors of 5 from one step
  // to the next where nothing grows (buck.cir at rtol 1e-7), and cutting on it alone rejected
  // ten times more steps there.
  const double growth_now = error_growth(error_k);
  const double growth = std::min(growth_now, last_accepted.growth);
  last_accepted = {order_used, error_k, h_used, growth_now};
  if (order_new == order - 1 || order >= std::min(options.max_order, kStartupOrder)) startup_phase = false;
  steps_past_kink = kink_count > 0 && kink_crossed() ? 0 : std::min(steps_past_kink + 1, kMaxOrder);
  // Order k + 1 interpolates k + 2 points, back to the one k steps before the step's start.
  const bool history_past_kink = steps_past_kink >= order;

  const double h_max = options.max_step > 0 ? options.max_step : std::numeric_limits<double>::infinity();
  // IDA's start-up: raise the order and double the step until a step fails or the order
  // drops; here only up to kStartupOrder.
  if (startup_phase) {
    if (history_past_kink) order = std::min(order + 1, options.max_order);
    h = std::min(2 * h, h_max);
  } else if (options.method == Method::trapezoidal) {
    // Back to the trapezoidal order after any backward-Euler step (repeated failures).
    order = options.max_order;
    choose_step(error_k, order_used, h_max, growth);
  } else {
    enum { lower, maintain, raise } action = maintain;
    double error_new = error_k;
    double error_k_plus_1 = 0;
    if (order_new == order - 1) {
      action = lower;
    } else if (order == options.max_order || order + 1 >= constant_steps || order_change == 1 || !history_past_kink) {
      action = maintain;
    } else {
      Vector above = correction_q - phi_q[order + 1];
      error_k_plus_1 = weighted_norm(above, inverse_weight_q, options.norm) / (order + 2);
      double terr_k = (order + 1) * error_k;
      double terr_k_plus_1 = (order + 2) * error_k_plus_1;
      if (order == 1) {
        action = terr_k_plus_1 >= 0.5 * terr_k ? maintain : raise;
      } else {
        double terr_k_minus_1 = order * error_k_minus_1;
        if (terr_k_minus_1 <= std::min(terr_k, terr_k_plus_1)) action = lower;
        else if (terr_k_plus_1 >= terr_k) action = maintain;
        else action = raise;
      }
    }
    if (action == raise) ++order, error_new = error_k_plus_1;
    if (action == lower) --order, error_new = error_k_minus_1;
    choose_step(error_new, order, h_max, action == maintain ? growth : 1);
  }

  if (options.method == Method::trapezoidal || started) q_derivative = q_derivative_predicted + cj * correction_q;
  correction_x.swap(previous_correction_x);  // storage swapped, not copied
  correction_x = x_new - x_predicted;
  if (order_used < options.max_order) {
    phi_x[order_used + 1] = correction_x;
    phi_q[order_used + 1] = correction_q;
  }
  phi_x[order_used] += correction_x;
  phi_q[order_used] += correction_q;
  for (int j = order_used - 1; j >= 0; --j) {
    phi_x[j] += phi_x[j + 1];
    phi_q[j] += phi_q[j + 1];
  }
  if (started) {
    // The history becomes the quadratic through q0 and q1 with slope q'1 at t1 (Hermite's):
    // the one through q1, q0 and a virtual point at t0 - h, whose second modified divided
    // difference is h^2 P'' = 2 (h q'1 - (q1 - q0)). x keeps the line through x0 and x1.
    psi[1] = 2 * h_used;
    phi_q[2] = 2 * (h_used * q_derivative - phi_q[1]);
    phi_x[2].setZero();
    order_used = 2;
    virtual_point_in_history = true;
  }
}

StepOutcome Integrator::Impl::step(double t_stop) {
  if (!(t_stop > t)) return fail(t, "step() called with t_stop " + format_number(t_stop, 17) + " not after t = " + format_number(t, 17));
  // A stop within the time resolution (a source corner computed an ulp before TSTOP): the state
  // at t is the state there, and a step that short would be singular (C / h swamps the rest).
  if (t_stop - t < minimum_step()) {
    t = t_stop;
    return {StepKind::stop, t};
  }
  const double t_old = t;
  step_predicates = p;
  const Vector guards_old = guards_now;

  update_weights();
  int error_test_failures = 0, newton_failures = 0;
  std::array<RejectedAttempt, kMaxErrorTestFailures> rejected;  // the first error_test_failures
  int blamed = -1;  // the worst unknown of the last rejected attempt: what shrinks the step
  bool left_domain = false;  // whether the last rejected attempt could not evaluate the model
  bool tried_minimum_step = false;
  double error = 0, error_k = 0, error_k_minus_1 = 0;
  int order_new = order;
  bool ends_at_target = false;
  double corner = 0, target = t_stop;
  for (;;) {
    if (options.max_step > 0) h = std::min(h, options.max_step);
    h_planned = h;
    const CornersAhead ahead = corners_ahead(std::min(t_stop, t + 1.0001 * h));
    corner = ahead.bending;
    h = std::min(h, ahead.last_passable - t);
    target = std::min(t_stop, corner);
    ends_at_target = t + h >= target || t + 1.0001 * h >= target;
    if (ends_at_target) h = target - t;
    if (h < minimum_step() && !ends_at_target) {
      // As SPICE does, the minimum step itself is tried once before giving up: a reduction by 4
      // can pass over the step the error test would accept.
      // A failure there at a higher order or at the trapezoidal start is retried by backward
      // Euler, whose step at the minimum is accepted whatever its error (unresolvable below).
      if (!tried_minimum_step || order > 1 || trapezoidal_start()) {
        if (tried_minimum_step) {
          order = 1;
          fast_mode_left = true;  // which is what the failure says: no trapezoidal start
        }
        tried_minimum_step = true;
        h = minimum_step();
        continue;
      }
      // Without a rejection here the accepted steps' error estimates shrank it.
      if (blamed < 0) weighted_max_norm(correction_q, inverse_weight_q, &blamed);
      return fail(t, "step size " + format_number(h, 17) + " s fell below the minimum step (" + format_number(minimum_step(), 3) +
                         " s) at t = " + format_number(t, 17) +
                         (left_domain ? ": the model cannot be evaluated (outside its domain) at the steps tried"
                          : unresolved_in_a_row >= kMaxUnresolvedSteps
                              ? ": a transient faster than that did not die out in " + std::to_string(kMaxUnresolvedSteps) + " such steps"
                              : ""),
                  blamed);
    }
    rescale_first_step();
    set_coefficients();
    predict();
    const double t_new = ends_at_target ? target : t + h;

    // The trapezoidal rule damps nothing, not even the bias a matrix of another cj leaves in
    // Newton's solution: it would accumulate into amplitude drift (an LC tank lost 4% over
    // 10,000 periods), so its matrix always has the step's cj.
    const double cj_change_allowed = trapezoidal_step() ? 0.0 : kJacobianCjChange;
    bool fresh = !have_matrix || std::abs(cj / cj_of_matrix - 1) > cj_change_allowed ||
                 statistics.steps >= step_of_matrix + kStepsBetweenJacobians || newton_was_slow;
    const long iterations_before = statistics.newton_iterations;
    NewtonOutcome correction = correct(t_new, fresh ? Newton::modified_fresh : Newton::modified);
    newton_was_slow = statistics.newton_iterations - iterations_before >= kSlowNewtonIterations;
    if (correction == NewtonOutcome::diverged && !fresh) correction = correct(t_new, Newton::modified_fresh);
    // A first attempt whose modified Newton diverged past the error test (diverged_past_error_test)
    // goes to the error test from its last iterate, which it fails, instead of to damped Newton;
    // a second attempt always gets damped Newton.
    const bool first_attempt = error_test_failures == 0 && newton_failures == 0;
    const bool failing = correction == NewtonOutcome::diverged && first_attempt && diverged_past_error_test();
    if (failing) q_new = q_predicted + iterate_charge_move;
    else if (correction == NewtonOutcome::diverged) correction = correct(t_new, Newton::full);
    retaking_at_kink = false;

    left_domain = correction == NewtonOutcome::outside_domain;
    if (correction != NewtonOutcome::converged && !failing) {
      restore();
      if (correction == NewtonOutcome::outside_domain) ++statistics.rejected_domain;
      else ++statistics.rejected_newton;
      weighted_max_norm(delta, inverse_weight_x, &blamed);
      if (correction == NewtonOutcome::singular) blamed = newton.singular_column();
      // IDA's first steps can be so short that rounding loses what ties a node down: 280 V into
      // 50 uH, its current held to 1 pA, gave 2e-19 s, where C / h swamps in every row the 1 uS
      // that holds the common mode of a diode island, and Newton failed however small the step
      // (or half the time, for ever). The step the motion's curvature allows (settle()'s q'')
      // is tried instead, once.
      if (first_step_by_curvature > h) {
        h = first_step_by_curvature;
        first_step_by_curvature = 0;
        have_matrix = false;
        continue;
      }
      if (++newton_failures >= kMaxNewtonFailures || h <= minimum_step()) {
        std::string why = correction == NewtonOutcome::singular
                              ? "the Newton matrix is singular (column " + std::to_string(newton.singular_column()) + ")"
                          : correction == NewtonOutcome::outside_domain
                              ? "the model cannot be evaluated (outside its domain) however small the step"
                              : "Newton's method does not converge however small the step";
        // A solution near the largest double (a linear E in positive feedback, 1.8e308 V) is
        // no domain's fault: it diverges, and its largest unknown is the one to name.
        int largest = 0;
        if (n > 0 && x.cwiseAbs().maxCoeff(&largest) > kOverflowing)
          return fail(t, "the solution grows without bound (" + format_number(x[largest], 3) +
                             " at t = " + format_number(t, 17) + ", near the largest number a double holds)",
                      largest, "an unstable circuit (positive feedback with a loop gain above 1?)");
        return fail(t, why + " at t = " + format_number(t, 17), blamed);
      }
      // The trapezoidal rule's corrector leans on q' at the step's start, and where that is a
      // ringing algebraic unknown's (a flyback's blocked secondary, v(sec) swinging +-200 V from
      // step to step) no step however short converged: retried at order 1, backward Euler, as
      // SPICE retries. BDF's correctors lean on no derivative; dropping their order too (SPICE
      // does) cost an LLC converter 22 % more factorizations at rtol 1e-8.
      h *= 0.25;
      if (trapezoidal_method_step()) {
        order = 1;
        startup_phase = false;
      }
      have_matrix = have_matrix && correction != NewtonOutcome::singular;
      continue;
    }

    // A transient faster than the time resolution (an inductor opened into 1e12 ohm at t = 0.1 s:
    // L / R = 1e-15 s, the minimum step 3.6e-16 s there) fails the error test at every step t can
    // represent. Backward Euler at the minimum step damps it as fast as its decay would be (it is
    // L-stable): that step is accepted, counted and reported; the transient's shape is lost, not
    // the state after it. One that has not died out in kMaxUnresolvedSteps steps is none, and
    // a growing mode (a regenerative latch), which backward Euler that far past its stability
    // boundary damps too, shows as a change against the last step's direction.
    const bool passed = error_test(error, error_k, error_k_minus_1, order_new);
    const bool unresolvable = !passed && order == 1 && !trapezoidal_step() && h <= minimum_step() &&
                              unresolved_in_a_row < kMaxUnresolvedSteps && continues_last_change();
    if (passed) {
      unresolved_in_a_row = 0;
    } else if (unresolvable) {
      ++unresolved_in_a_row;
      ++statistics.unresolved_steps;
      if (!unresolved) {
        int worst = -1;
        weighted_max_norm(correction_q, inverse_weight_q, &worst);
        unresolved = UnresolvedTransient{t, minimum_step(), worst};
      }
    }
    if (!passed && !unresolvable) {
      restore();
      ++statistics.rejected_error_test;
      rejected[error_test_failures++] = {order, h, error};
      weighted_max_norm(correction_q, inverse_weight_q, &blamed);
      if (error_test_failures >= kMaxErrorTestFailures) {
        return fail(t, "the error test failed repeatedly at t = " + format_number(t, 17), blamed,
                    unfalling_error(std::span(rejected.data(), error_test_failures)));
      }
      // A first failure at order 2 is retried at order 2, even where IDA's rule would lower
      // it: backward Euler's error has one sign at every such step of a periodic circuit and
      // adds up over the periods, which is why a restart begins with the trapezoidal rule. An
      // ideal flyback in discontinuous conduction at rtol 1e-3 ran 13.6 % low, each diode
      // conduction phase ending in a backward-Euler step that fell short of its charge. Not
      // where a fast mode was left to the integration: that is backward Euler's to damp.
      if (order == 2 && error_test_failures == 1 && !fast_mode_left) order_new = 2;
      double error_new = order_new == order ? error_k : error_k_minus_1;
      order = order_new;
      if (error_test_failures == 1) {
        double ratio = 0.9 * step_ratio(error_new, order);
        h *= std::clamp(ratio, 0.25, 0.9);
      } else {
        if (error_test_failures > 2) order = 1;
        h *= 0.25;
      }
      startup_phase = false;
      continue;
    }
    if (kink_spoils_derivative()) {
      // The same step at order 1, whose derivative (the secant) cannot overshoot; Newton starts
      // from this attempt's solution, close to the new one.
      retake_start = x_new;
      retaking_at_kink = true;
      restore();
      ++statistics.retaken_at_kinks;
      order = 1;
      startup_phase = false;  // which would raise the order again at once
      continue;
    }
    // Steps as long as the start's curvature allowed: the start is over (first_step_by_curvature).
    if (t_new - t >= first_step_by_curvature) first_step_by_curvature = 0;
    complete_step(error_k, error_k_minus_1, order_new);
    corner_inside = next_time_event < t_new;
    t = t_new;
    anchor = t_new;
    x = x_new;
    kinks_now.swap(kinks_new);
    break;
  }

  if (predicate_count > 0) {
    Vector guards_new(predicate_count);
    if (!evaluate_guards(t, x, guards_new)) return fail(t, "a guard function cannot be evaluated at t = " + format_number(t, 17));
    // A corner the step passed can still bend a guard (the ramp of a gate drive): the guards
    // are sampled there too, and the first crossing is located between samples.
    double t_left = t_old;
    Vector guards_left = guards_old;
    for (double passed = next_time_event; passed < t; passed = system.next_time_event(passed)) {
      Vector guards_passed(predicate_count);
      if (!evaluate_guards(passed, located_solution(passed), guards_passed))
        return fail(passed, "a guard function cannot be evaluated at t = " + format_number(passed, 17));
      if (crossed(guards_passed)) return handle_state_event(t_left, guards_left, passed, guards_passed);
      if (auto inside = crossing_inside(t_left, guards_left, passed, guards_passed))
        return handle_state_event(t_left, guards_left, inside->t, inside->guards);
      t_left = passed;
      guards_left = std::move(guards_passed);
    }
    if (auto inside = crossing_inside(t_left, guards_left, t, guards_new))
      return handle_state_event(t_left, guards_left, inside->t, inside->guards);
    if (crossed(guards_new)) return handle_state_event(t_left, guards_left, t, guards_new);
    guards_now = guards_new;
  }

  if (ends_at_target && target == corner) {
    ++statistics.time_events;
    // At a source corner the derivatives are discontinuous, and the source itself may jump
    // (a sawtooth's reset): the event procedure makes the state consistent on the right side
    // and settles the predicates there; the BDF restarts at order 1.
    if (!settle(t, x, p, true)) return {StepKind::failed, t};
    const bool discontinuous = !last_event.flips.empty() || last_event.jumped ||
                               weighted_max_norm(last_event.x_after - last_event.x_before, inverse_weight_x) > 1;
    if (discontinuous) {
      ++statistics.events;
      return {StepKind::event, t};
    }
    return {t == t_stop ? StepKind::stop : StepKind::time_event, t};
  }
  while (next_time_event <= t) next_time_event = system.next_time_event(next_time_event);
  if (ends_at_target) return {StepKind::stop, t};
  return {StepKind::accepted, t};
}

bool Integrator::Impl::evaluate_guards(double t_at, const Vector& x_at, Vector& out) const {
  out.setZero(predicate_count);
  return system.guards(t_at, x_at, out) == EvalStatus::ok;
}

bool Integrator::Impl::crossed(const Vector& guards) const {
  for (int k = 0; k < predicate_count; ++k)
    if ((guards[k] > 0) != (p[k] != 0)) return true;
  return false;
}

// A clamp's ideal diode conducts for a microsecond at the peak of a sine that a step crossed in
// five: its guard is back below zero at the step's end. Screened on the step's polynomial (no
// solve): at the midpoint, and, for a guard whose margin (positive once crossed) bends down
// between the ends, at the vertex of the parabola through its margins at the ends and the
// midpoint. A crossing seen there is confirmed on the solution, which the event location then
// uses.
std::optional<Integrator::Impl::GuardSample> Integrator::Impl::crossing_inside(double t_left, const Vector& guards_left,
                                                                                double t_right, const Vector& guards_right) {
  const double half = 0.5 * (t_right - t_left), t_middle = t_left + half;
  Vector& guards = screened_guards;
  guards.resize(predicate_count);
  interpolate(t_middle, screened_state);
  if (!evaluate_guards(t_middle, screened_state, guards)) return std::nullopt;
  if (crossed(guards)) return confirmed_crossing(t_middle);
  std::vector<double>& vertices = screened_times;
  vertices.clear();
  for (int k = 0; k < predicate_count; ++k) {
    const double sign = p[k] ? -1.0 : 1.0;
    const double before = sign * guards_left[k], at = sign * guards[k], after = sign * guards_right[k];
    const double curvature = before - 2 * at + after;
    if (!(curvature < 0)) continue;
    const double offset = 0.5 * (before - after) / curvature;  // in half steps
    if (std::abs(offset) < 1 && at - 0.25 * (before - after) * offset > 0) vertices.push_back(t_middle + offset * half);
  }
  // Guards driven by one source (switches on one clock) share their vertex: sampled once.
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  for (double t_at : vertices) {
    interpolate(t_at, screened_state);
    if (!evaluate_guards(t_at, screened_state, guards)) return std::nullopt;
    if (crossed(guards)) return confirmed_crossing(t_at);
  }
  return std::nullopt;
}

std::optional<Integrator::Impl::GuardSample> Integrator::Impl::confirmed_crossing(double t_at) {
  Vector guards(predicate_count);
  if (!evaluate_guards(t_at, located_solution(t_at), guards) || !crossed(guards)) return std::nullopt;
  return GuardSample{t_at, std::move(guards)};
}

DenseOutput& Integrator::Impl::locator() {
  if (!location_solver) location_solver = std::make_unique<DenseOutput>(system, statistics, options, resolvable_tolerance);
  return *location_solver;
}

// The step's end holds the guards found at t_right (the step's end or a corner it passed).
StepOutcome Integrator::Impl::handle_state_event(double t_left, const Vector& guards_left, double t_right,
                                                 const Vector& guards_right) {
  // Locate the earliest crossing on the solution inside the step: on the interpolating
  // polynomial itself an algebraic unknown (a source's node) is off by the polynomial's error,
  // and a guard on it crosses early or late.
  auto guards_at = [&](double t_at, Vector& out) { return evaluate_guards(t_at, located_solution(t_at), out); };
  const double tolerance = 100 * kEps * (std::abs(t_right) + std::abs(h_used));
  Crossing crossing = locate_first_crossing(guards_at, p, t_left, guards_left, t_right, guards_right, tolerance);
  if (!crossing.ok) return fail(t, "a guard function cannot be evaluated while locating an event near t = " + format_number(t, 17));

  const double t_event = crossing.t_right;
  const Vector x_before = located_solution(t_event);
  Predicates target = p;
  for (int k = 0; k < predicate_count; ++k) target[k] = crossing.guards_right[k] > 0;
  // Accumulation (Zeno): events closer than the time resolution, or intervals shrinking
  // geometrically; the accumulation point is extrapolated from the last two intervals.
  const double interval = t_event - last_event_time;
  events_in_burst = interval <= 100 * minimum_step() ? events_in_burst + 1 : 0;
  shrinking_intervals = interval <= kAccumulationRatio * last_event_interval ? shrinking_intervals + 1 : 0;
  const double ratio = interval / last_event_interval;
  last_event_time = t_event;
  last_event_interval = interval;
  if (events_in_burst >= options.max_events_in_burst || shrinking_intervals >= kAccumulationEvents) {
    double limit = shrinking_intervals >= kAccumulationEvents ? t_event + interval * ratio / (1 - ratio) : t_event;
    std::string which;
    for (int k = 0; k < predicate_count; ++k)
      if (target[k] != p[k]) which += (which.empty() ? "" : ", ") + std::to_string(k);
    t = t_event;
    x = x_before;
    return fail(t_event, "event accumulation at t = " + format_number(limit, 17) + ": the intervals between events of predicate " + which +
                             " shrink to zero (Zeno behaviour, or chattering where both modes head across the switching"
                             " surface); stopped at t = " + format_number(t_event, 17));
  }

  t = t_event;
  const Predicates mode_before = p;
  if (!settle(t_event, x_before, target, true)) return {StepKind::failed, t};
  // A crossing located within the guard's tolerance of a tangency (a clamp's diode turning off
  // at the sine's peak, its current and voltage at their thresholds together) can lead to a mode
  // that heads straight back: the fixed point then ends in the mode it left, nothing changed,
  // and the step ends as an ordinary one (restarted), the real crossing being the next event.
  if (p == mode_before && !last_event.jumped) return {StepKind::accepted, t};
  ++statistics.events;
  return {StepKind::event, t};
}

// The event procedure: jumps (form (5), e from convention (9)), consistent re-initialization
// and the predicate fixed point.
bool Integrator::Impl::settle(double t_at, const Vector& x_start, const Predicates& target_in,
                              bool record_flips) {
  last_event = EventRecord{};
  last_event.t = t_at;
  last_event.x_before = x_start;
  // The re-initialization's steps and the restart's first ones are the shortest, and divide the
  // charges' rounding by h: measured from here, the charges are small.
  measure_charges_from(t_at, x_start);
  Vector x_jumped = x_start;
  Predicates target = target_in;
  std::vector<char> flipped_here(static_cast<std::size_t>(predicate_count), 0);
  std::vector<JumpEntry> jump_entries;
  std::optional<ConsistentState> consistent;
  const double h_reference = h > 0 ? h : first_step_estimate(t_at, x_start);
  std::vector<Predicates> left_modes;  // the fixed point's modes so far
  std::size_t flips_to_first_mode = 0;  // the flips recorded when left_modes.front() was reached
  bool back_to_first_mode = false;
  // A mode without a consistent state whose guards name no other change: its single flips are
  // tried in turn, from the predicates the event itself did not flip.
  std::optional<Predicates> stalled_mode;
  std::vector<char> flipped_by_event;
  int next_single_flip = 0;
  // The flips the located crossing itself asks for (none at the start): a singular mode is left
  // by undoing the fixed point's flips only where keeping them all leaves no other way.
  std::vector<char> crossed(static_cast<std::size_t>(predicate_count), 0);
  for (int k = 0; k < predicate_count; ++k) crossed[k] = target_in[k] != p[k];

  for (int iteration = 1;; ++iteration) {
    if (iteration > options.max_event_iterations) {
      std::string which;
      for (int k = 0; k < predicate_count; ++k)
        if (flipped_here[k]) which += (which.empty() ? "" : ", ") + std::to_string(k);
      failure = Failure{t_at, "event accumulation (chattering) at t = " + format_number(t_at, 17) +
                                  ": predicates " + which + " do not settle after " +
                                  std::to_string(options.max_event_iterations) + " flips",
                        -1};
      return false;
    }
    last_event.iterations = iteration;
    const Vector x_unjumped = x_jumped;  // what a retry in another mode jumps from
    const bool jumped_before = last_event.jumped;
    if (system.has_jumps() && target != p) {
      jump_entries.clear();
      system.jump_matrix(t_at, x_jumped, p, jump_entries);
      for (const JumpEntry& entry : jump_entries) {
        if (target[entry.predicate] == p[entry.predicate] || entry.value == 0) continue;
        x_jumped[entry.row] += entry.value * (target[entry.predicate] ? 1.0 : -1.0);
        // A mode held in an auxiliary unknown changing is not a jump of the state.
        if (!newton.is_auxiliary(entry.row)) last_event.jumped = true;
      }
    }
    if (back_to_first_mode) last_event.flips.resize(flips_to_first_mode);
    const std::size_t flips_before = last_event.flips.size();
    for (int k = 0; k < predicate_count; ++k) {
      if (target[k] == p[k]) continue;
      flipped_here[k] = 1;
      if (record_flips && !back_to_first_mode) last_event.flips.push_back({k, p[k] != 0, target[k] != 0});
    }
    Predicates previous = p;
    p = target;
    consistent = reinitializer.jump(t_at, x_jumped, previous, p, h_reference);
    const std::optional<Vector>& failed_at =
        reinitializer.stalled_state() ? reinitializer.stalled_state() : reinitializer.outside_domain_state();
    // Where the new mode leaves a direction undetermined: continuation stalled near it, or its
    // matrix is singular.
    const std::optional<Vector>& undetermined_at =
        reinitializer.stalled_state() ? reinitializer.stalled_state() : reinitializer.singular_state();
    if (!consistent && (failed_at || undetermined_at) && predicate_count > 0) {
      std::optional<Predicates> retry;
      // The new mode has no consistent state; the guards where continuation stalled say which
      // other predicates change with the ones that flipped (the diode that an ideal switch
      // closing across it turns off), and so do the guards where the mode left its domain (a
      // guard at zero at the event, on its other side as the motion goes on).
      Vector guards_stalled(predicate_count);
      if (failed_at && evaluate_guards(t_at, *failed_at, guards_stalled)) {
        Predicates rescue = p;
        for (int k = 0; k < predicate_count; ++k)
          if (!flipped_here[k]) rescue[k] = guards_stalled[k] > 0;
        if (rescue != p) retry = rescue;
      }
      // No guard there says which. An ideal switch closing across a conducting ideal diode,
      // both without resistance or forward voltage, leaves the split of the current between them
      // undetermined; with the diode off it is not, and the diode's guard (its voltage, 0) keeps
      // it off. So first the predicates whose guards move along what the mode leaves undetermined
      // flip, one per undetermined direction (the two legs of a full bridge; a current source's
      // diodes, off at a start from initial conditions); then the modes with one more predicate
      // flipped, each in turn.
      if (!retry && undetermined_at) {
        if (!stalled_mode) {
          stalled_mode = p, flipped_by_event = flipped_here;
          for (const std::vector<char>* kept : {&flipped_by_event, &crossed}) {
            const Predicates undetermined = undetermined_flipped(t_at, *undetermined_at, p, 1 / h_reference, *kept);
            if (undetermined != p) {
              retry = undetermined;
              break;
            }
          }
        }
        while (!retry && next_single_flip < predicate_count && flipped_by_event[next_single_flip]) ++next_single_flip;
        if (!retry && next_single_flip < predicate_count) {
          retry = *stalled_mode;
          (*retry)[next_single_flip] = !(*retry)[next_single_flip];
          ++next_single_flip;
          flipped_here = flipped_by_event;
        }
      }
      if (retry) {
        // The failed attempt is undone: the retry jumps from the state before it and records
        // its own flips.
        p = previous;
        target = *retry;
        x_jumped = x_unjumped;
        last_event.jumped = jumped_before;
        last_event.flips.resize(flips_before);
        continue;
      }
    }
    if (!consistent) {
      failure = Failure{t_at, reinitializer.failure_reason() + " at t = " + format_number(t_at, 17),
                        reinitializer.failure_unknown()};
      return false;
    }
    if (predicate_count == 0 || back_to_first_mode) break;
    // Convention (9) for the new mode. A predicate that flipped here is judged by where the new
    // motion is heading (just after t): its new guard starts at zero up to the old guard's
    // resolution, amplified by the new mode (an ideal diode's current is its voltage error
    // over RON), so the flip stands unless the guard is both on the other side and moving away.
    // The others are judged on the jump itself, impulses included (the voltage spike of a broken
    // inductor current turns a freewheeling diode on).
    Vector guards_after(predicate_count), guards_start(predicate_count), guards_heading(predicate_count);
    if (!evaluate_guards(t_at, consistent->x_impulse, guards_after) ||
        !evaluate_guards(t_at, consistent->x, guards_start) ||
        !evaluate_guards(consistent->t_heading, consistent->x_heading, guards_heading)) {
      failure = Failure{t_at, "a guard function cannot be evaluated after the event at t = " + format_number(t_at, 17), -1};
      return false;
    }
    Predicates next = p;
    for (int k = 0; k < predicate_count; ++k) {
      if (!flipped_here[k]) {
        next[k] = guards_after[k] > 0;
        continue;
      }
      const bool on_side = guards_heading[k] > 0, rising = guards_heading[k] > guards_start[k];
      next[k] = p[k] ? (on_side || rising) : (on_side && rising);
    }
    if (next == p) break;
    // A mode the fixed point has left already: at a tangency (a clamp's ideal diode turning off
    // where its current and its voltage reach their thresholds together) each mode's heading is
    // off by the solution's tolerance, and each sends it to the other. The first mode the
    // located crossing led to decides: the motion goes on in it, and a real return is an event
    // of its own.
    if (left_modes.empty()) flips_to_first_mode = last_event.flips.size();
    left_modes.push_back(p);
    if (std::find(left_modes.begin(), left_modes.end(), next) != left_modes.end()) {
      if (p == left_modes.front()) break;
      back_to_first_mode = true;
      next = left_modes.front();
    }
    target = next;
  }
  last_event.x_after = consistent->x;
  last_event.impulse = consistent->impulse;
  last_event.jumped = last_event.jumped || consistent->charges_moved;
  if (last_event.jumped) ++statistics.jumps;
  restart(t_at, *consistent);
  return true;
}

// The mode with as few predicates flipped (none of those in `kept`) as make the mode's equations
// at x regular: while they are singular (the current around a loop of ideal elements left
// undetermined), the predicate whose guard moves most along the undetermined direction flips.
// Inverse iteration on the matrix shifted by far less than any conductance finds that direction:
// it grows by the inverse shift, every other by far less.
Predicates Integrator::Impl::undetermined_flipped(double t_at, const Vector& x_at, const Predicates& mode,
                                                  double cj, const std::vector<char>& kept) {
  constexpr double kShift = 1e-12;
  Predicates flipped = mode;
  std::vector<char> fixed = kept;
  Vector guards_at(predicate_count), guards_moved(predicate_count), direction(n);
  if (!evaluate_guards(t_at, x_at, guards_at)) return mode;
  while (newton.factor(t_at, x_at, flipped, cj) == NewtonMatrix::Outcome::singular) {
    if (newton.factor_shifted(t_at, x_at, flipped, kShift, cj) != NewtonMatrix::Outcome::ok) return mode;
    // Signs and sizes from scrambled bits: a start with a component along every direction
    // (equal entries would cancel along a loop of two equal branches).
    for (int i = 0; i < n; ++i) {
      const std::uint32_t hash = scrambled(i + 1);
      direction[i] = (hash & 0x8000u ? -1.0 : 1.0) * (1 + static_cast<double>(hash >> 22) / 1024);
    }
    for (int iteration = 0; iteration < 2; ++iteration) {
      newton.solve(direction);
      const double norm = weighted_max_norm(direction, inverse_weight_x);
      if (!(norm > 0) || !std::isfinite(norm)) return mode;
      direction /= norm;
    }
    if (!evaluate_guards(t_at, x_at + direction, guards_moved)) return mode;
    int most = -1;
    for (int k = 0; k < predicate_count; ++k)
      if (!fixed[k] && (most < 0 || std::abs(guards_moved[k] - guards_at[k]) > std::abs(guards_moved[most] - guards_at[most])))
        most = k;
    if (most < 0 || guards_moved[most] == guards_at[most]) return mode;
    flipped[most] = !flipped[most];
    fixed[most] = 1;
  }
  return flipped;
}

// Before the first step: IDA's estimate, the first-order change over the step within half a
// tolerance, from q' = -f at the (not yet consistent) initial state.
double Integrator::Impl::first_step_estimate(double t_at, const Vector& x_at) {
  if (options.initial_step > 0) return options.initial_step;
  double h_first = 1e-3 * options.time_scale;
  if (newton.evaluate(t_at, x_at, p) != EvalStatus::ok) return h_first;
  Vector q_rate = -newton.load().f;
  newton.keep_dynamic_rows(q_rate);
  const double rate = weighted_norm(q_rate, inverse_weight_q, options.norm);
  return h_first * rate > 0.5 ? 0.5 / rate : h_first;
}

// IDA's IDAGetSolution (IDAGetDky for the derivative): the interpolating polynomial of the
// last step.
Vector Integrator::Impl::interpolate(double t_at, Interpolated what, Quantity of) const {
  Vector result;
  interpolate(t_at, result, what, of);
  return result;
}

void Integrator::Impl::interpolate(double t_at, Vector& out, Interpolated what, Quantity of) const {
  const StepView step = last_step();
  const auto weights = polynomial_weights(step.anchor, step.order, step.psi, t_at, what);
  const auto& phi = of == Quantity::x ? step.phi_x : step.phi_q;
  out = weights[0] * phi[0];
  for (int j = 1; j <= step.order; ++j) out += weights[j] * phi[j];
}

void Integrator::Impl::interpolate(double t_at, std::span<const int> unknowns, Vector& out) const {
  const StepView step = last_step();
  const auto weights = polynomial_weights(step.anchor, step.order, step.psi, t_at, Interpolated::value);
  for (int i : unknowns) {
    double value = step.phi_x[0][i];
    for (int j = 1; j <= step.order; ++j) value += weights[j] * step.phi_x[j][i];
    out[i] = value;
  }
}

Integrator::Impl::StepView Integrator::Impl::last_step() const {
  if (after_restart())
    return {previous_step.anchor, previous_step.order, previous_step.phi_x, previous_step.phi_q,
            previous_step.psi, previous_step.p, previous_step.number, previous_step.corner_inside};
  return {anchor, order_used, phi_x, phi_q, psi, step_predicates, statistics.steps, corner_inside};
}

// w_j = c_j(t), the product over i < j of (t - anchor + psi_{i-1}) / psi_i (psi_{-1} = 0); the
// derivative differentiates the products.
std::array<double, kHistory> Integrator::Impl::polynomial_weights(double anchor_at, int order_of,
                                                                  const std::array<double, kHistory>& psi_of,
                                                                  double t_at, Interpolated what) {
  const bool derivative = what == Interpolated::derivative;
  std::array<double, kHistory> weights{};
  weights[0] = derivative ? 0 : 1;
  double delta_t = t_at - anchor_at;
  double c = 1, c_derivative = 0, gam = delta_t / psi_of[0];
  for (int j = 1; j <= order_of; ++j) {
    c_derivative = c_derivative * gam + c / psi_of[j - 1];
    c *= gam;
    gam = (delta_t + psi_of[j - 1]) / psi_of[j];
    weights[j] = derivative ? c_derivative : c;
  }
  return weights;
}

RowRefinement::Row Integrator::Impl::row_source(double t_at, std::span<const int> unknowns) {
  using Row = RowRefinement::Row;
  const StepView step = last_step();
  if (step.order == 0) return Row::polynomial;  // a point: no step yet
  if (step.corner_inside)
    for (int i : unknowns)
      if (corner_can_reach[i]) return Row::solved;
  bool planned = row_plan.step == step.number && row_plan.unknowns.size() == unknowns.size();
  for (std::size_t k = 0; planned && k < unknowns.size(); ++k) planned = row_plan.unknowns[k] == unknowns[k];
  if (!planned) {
    row_plan.step = step.number;
    row_plan.unknowns.assign(unknowns.begin(), unknowns.end());
    row_plan.polynomial = charges_determine(unknowns) || step_vouches_for_polynomial(unknowns);
  }
  if (row_plan.polynomial) return Row::polynomial;
  if (output_refinement.step() != step.number) output_refinement.reset(step.number, step.anchor - step.psi[0], step.anchor);
  return output_refinement.row(t_at, unknowns, inverse_weight_x);
}

bool Integrator::Impl::charges_determine(std::span<const int> unknowns) {
  const StepView step = last_step();
  if (charge_determined.unknowns.empty() || charge_determined.mode != step.p) {
    charge_determined.mode = step.p;
    if (writer().charge_determined(step.anchor, step.phi_x[0], step.p, charge_determined.unknowns) != EvalStatus::ok)
      charge_determined.unknowns.assign(static_cast<std::size_t>(n), 0);
  }
  for (int i : unknowns)
    if (!charge_determined.unknowns[i]) return false;
  return true;
}

// The polynomial S through x at the step's end and the points before serves the rows where the
// step itself shows it, at the cost of one solve on the factorization held:
//  - the predictor, the polynomial through the points before, missed x at the step's end by at
//    most the tolerance, on this step and the one before. For a smooth solution S then misses
//    it inside the step by far less: at the step's middle, by 1/8 of the predictor's miss at
//    order 1 with equal steps, 1/16 at order 2, less at higher orders. One predictor can hit
//    by chance where the solution turns (a bridge rectifier's junction starting to conduct:
//    misses of 2.3, 0.47 and 9.8 tolerances on three steps in a row; S missed the checked
//    rows by 1.65);
//  - the local error of the charges, through the Newton matrix (its response in x, as
//    kink_spoils_derivative() weighs it), moves x by at most the tolerance. The solution inside
//    the step (dense_output.hpp) differs from S by about that response, many times the
//    tolerance where a small resistance ties an unknown to a charge (the bridge's junction
//    current through its 20 mOhm RS: S missed the checked rows by 8.6 tolerances with its
//    predictor within one).
// On the report's five switched netlists at rtol 1e-2 ... 1e-8, the rows so written are within
// 0.071 of the tolerance of the rows the checks gave. The solve waits for the predictors.
bool Integrator::Impl::step_vouches_for_polynomial(std::span<const int> unknowns) {
  // Two steps since the restart: both corrections are of this history.
  if (after_restart() || !have_matrix || statistics.steps - steps_at_restart < 2) return false;
  auto within = [&](const Vector& miss) {
    for (int i : unknowns)
      if (!(std::abs(miss[i]) * inverse_weight_x[i] <= 1)) return false;
    return true;
  };
  if (!within(correction_x) || !within(previous_correction_x)) return false;
  error_response = (cj * error_coefficient) * correction_q;
  newton.solve(error_response);
  return within(error_response);
}

DenseOutput& Integrator::Impl::writer() {
  if (!output_solver) output_solver = std::make_unique<DenseOutput>(system, output_statistics, options, resolvable_tolerance);
  return *output_solver;
}

Vector Integrator::Impl::located_solution(double t_at) {
  if (const Vector* remembered = remembered_solution(t_at)) return *remembered;
  if (located_step != last_step().number) {
    located.clear();
    located_step = last_step().number;
  }
  located.push_back({t_at, solution_or_polynomial(locator(), statistics, t_at)});
  return located.back().x;
}

const Vector* Integrator::Impl::remembered_solution(double t_at) const {
  if (located_step != last_step().number) return nullptr;
  for (const Located& point : located)
    if (point.t == t_at) return &point.x;
  return nullptr;
}

Vector Integrator::Impl::solution_or_polynomial(DenseOutput& solver, Statistics& counted_in, double t_at) const {
  if (auto solved = step_solution(solver, t_at)) return std::move(*solved);
  ++counted_in.unsolved_points;
  return interpolate(t_at);
}

std::optional<Vector> Integrator::Impl::step_solution(DenseOutput& solver, double t_at, const Vector* guess) const {
  const StepView step = last_step();
  // The points S passes through before the step's end are t_j = end - psi_j, j < order.
  auto c_at = [&](double t_of) {
    double sum = 0;
    for (int j = 0; j < step.order; ++j) sum += 1 / (t_of - (step.anchor - step.psi[j]));
    return sum;
  };
  // Close to the step's start c grows without bound, and with it the matrix's condition: c
  // stays within kMaxStiffening of its value at the step's end, where q is pinned to S within
  // a thousandth of the step's residual anyway.
  const double c_max = kMaxStiffening * c_at(step.anchor);
  // Newton from guess, or without one from where DenseOutput::solve chooses.
  auto solve_at = [&](double t_of, const Vector* start) {
    return solver.solve(step.number, t_of, start, interpolate(t_of),
                        interpolate(t_of, Interpolated::value, Quantity::q),
                        interpolate(t_of, Interpolated::derivative, Quantity::q), step.p,
                        std::min(c_at(t_of), c_max));
  };
  if (step.order == 0) return interpolate(t_at);
  if (auto solved = solve_at(t_at, guess)) return std::move(*solved);
  // Newton from the polynomial can fail where it is far from the solution (the common mode of
  // a load floating between junctions): continuation from the step's start, where the state is
  // known, through points each twice as far from it, each solve starting from the last.
  const double step_start = step.anchor - step.psi[0];
  Vector x = interpolate(step_start);
  for (int halvings = kContinuationHalvings; halvings >= 0; --halvings) {
    auto solved = solve_at(step_start + std::ldexp(t_at - step_start, -halvings), &x);
    if (!solved) return std::nullopt;
    x = std::move(*solved);
  }
  return x;
}

void Integrator::Impl::measure_charges_from(double t_at, const Vector& x_at) {
  if (newton.evaluate(t_at, x_at, p) != EvalStatus::ok) return;
  const Vector shift = newton.load().q;
  if (!system.measure_charges_from(t_at, x_at, p)) return;
  phi_q[0] -= shift;
  if (previous_step.order > 0) previous_step.phi_q[0] -= shift;
}

// Order 1 from a consistent state, as after the initial point (IDA's first step).
void Integrator::Impl::restart(double t_at, const ConsistentState& consistent) {
  steps_at_restart = statistics.steps;
  // Assigned member by member: the vectors keep their storage (a restart at every event).
  if (order_used > 0) {
    previous_step.anchor = anchor;
    previous_step.order = order_used;
    previous_step.phi_x = phi_x;
    previous_step.phi_q = phi_q;
    previous_step.psi = psi;
    previous_step.p = step_predicates;
    previous_step.number = statistics.steps;
    previous_step.corner_inside = corner_inside;
  }
  anchor = t_at;
  t = t_at;
  x = consistent.x;
  next_time_event = system.next_time_event(t);
  if (predicate_count > 0) evaluate_guards(t, x, guards_now);
  if (kink_count > 0) system.kinks(x, kinks_now);
  update_weights();
  double h_new = h > 0 ? std::max(h, h_planned) : (options.initial_step > 0 ? options.initial_step : 1e-3 * options.time_scale);
  // Order 1's local error, h^2 q'' / 2, bounded (unless the caller chose the initial step):
  // the new motion's curvature sets the first step, the previous step only caps it.
  double curvature = weighted_norm(consistent.q_second_derivative, inverse_weight_q, options.norm);
  if ((h > 0 || options.initial_step <= 0) && h_new * h_new * curvature > kRestartCurvatureBound)
    h_new = std::sqrt(kRestartCurvatureBound / curvature);
  first_step_by_curvature = 0;
  if (h <= 0 && options.initial_step <= 0) {
    first_step_by_curvature = h_new;
    // IDA's initial step: the first-order change over the step is at most half a tolerance.
    double rate = weighted_norm(consistent.q_derivative, inverse_weight_q, options.norm);
    if (h_new * rate > 0.5) h_new = 0.5 / rate;
  }
  if (options.max_step > 0) h_new = std::min(h_new, options.max_step);
  h_new = std::max(h_new, minimum_step());
  h = h_new;
  for (auto& v : phi_x) v.setZero();
  for (auto& v : phi_q) v.setZero();
  phi_x[0] = consistent.x;
  phi_q[0] = consistent.q;
  phi_x[1] = h * consistent.x_derivative;
  phi_q[1] = h * consistent.q_derivative;
  q_derivative = consistent.q_derivative;
  order = 1;
  order_used = 0;
  fast_mode_left = consistent.fast_mode_left;
  virtual_point_in_history = false;
  last_accepted = {};
  steps_past_kink = kMaxOrder;
  h_used = 0;
  have_matrix = false;  // re-initialization factored its own matrices
  psi[0] = h;
  cj = 1 / h;
  constant_steps = 0;
  startup_phase = true;
}

// --- Integrator ------------------------------------------------------------------------------

Integrator::Integrator(System& system, Options options)
    : impl_(std::make_unique<Impl>(system, options)) {}
Integrator::~Integrator() = default;

bool Integrator::initialize(double t0, const Vector& x0) {
  Predicates p0(static_cast<std::size_t>(impl_->predicate_count), 0);
  if (impl_->predicate_count > 0) {
    Vector guards(impl_->predicate_count);
    if (!impl_->evaluate_guards(t0, x0, guards)) {
      impl_->failure = Failure{t0, "a guard function cannot be evaluated at the initial state", -1};
      return false;
    }
    for (int k = 0; k < impl_->predicate_count; ++k) p0[k] = guards[k] > 0;
  }
  return initialize(t0, x0, p0);
}

bool Integrator::initialize(double t0, const Vector& x0, const Predicates& p0) {
  SubnormalsFlushed flushed;
  Impl& s = *impl_;
  if (x0.size() != s.n || static_cast<int>(p0.size()) != s.predicate_count) {
    s.failure = Failure{t0, "initial state has the wrong size", -1};
    return false;
  }
  s.t = t0;
  s.x = x0;
  s.p = p0;
  s.h = 0;
  s.peak_magnitude = x0.cwiseAbs();
  s.located.clear();
  s.located_step = -1;
  s.output_refinement.forget();
  s.update_weights();
  // The initial point is made consistent as an event is (jump projection, predicate fixed
  // point); that is the start, not an event, so it is neither counted nor recorded.
  if (!s.settle(t0, x0, p0, true)) return false;
  s.statistics.jumps = 0;
  s.last_event = EventRecord{};
  return true;
}

StepOutcome Integrator::step(double t_stop) {
  SubnormalsFlushed flushed;
  return impl_->step(t_stop);
}
double Integrator::time() const { return impl_->t; }
const Vector& Integrator::state() const { return impl_->x; }
const Predicates& Integrator::predicates() const { return impl_->p; }
int Integrator::order() const { return impl_->order_used; }
double Integrator::step_size() const { return impl_->h_used; }
const EventRecord& Integrator::last_event() const { return impl_->last_event; }
const Failure& Integrator::failure() const { return impl_->failure; }
const Statistics& Integrator::statistics() const { return impl_->statistics; }
const Statistics& Integrator::output_statistics() const { return impl_->output_statistics; }
const std::optional<UnresolvedTransient>& Integrator::unresolved_transient() const { return impl_->unresolved; }

Vector Integrator::interpolate(double t_at) const { return impl_->interpolate(t_at); }
Vector Integrator::dense_output(double t_at) { return dense_output(t_at, impl_->every_unknown); }
const Vector& Integrator::dense_output(double t_at, std::span<const int> unknowns) {
  SubnormalsFlushed flushed;
  Impl& s = *impl_;
  if (const Vector* located = s.remembered_solution(t_at)) return *located;
  const RowRefinement::Row source = s.row_source(t_at, unknowns);
  switch (source) {
    case RowRefinement::Row::polynomial:
    case RowRefinement::Row::interpolated:
      s.output_row.resize(s.n);
      s.interpolate(t_at, unknowns, s.output_row);
      if (source == RowRefinement::Row::interpolated) s.output_refinement.interpolate(t_at, unknowns, s.output_row);
      break;
    case RowRefinement::Row::solved:
      s.output_row = s.solution_or_polynomial(s.writer(), s.output_statistics, t_at);
      break;
  }
  return s.output_row;
}

}  // namespace padae
