// Event handling corner cases: an event at t0, inside the first step, simultaneous events, a
// jump that flips a further predicate, and chattering that must be diagnosed, not looped on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "padae/integrator.hpp"
#include "padae/newton_matrix.hpp"
#include "padae/semi_explicit.hpp"
#include "run_until.hpp"

namespace padae {
namespace {

using testing::run_until;
constexpr auto D = UnknownKind::differential;
constexpr auto A = UnknownKind::algebraic;
constexpr auto X = UnknownKind::auxiliary;

// x' = (p | 2 | 1), p = (x > 0): the slope doubles when x crosses zero upward.
class SlopeChange : public SemiExplicitSystem {
 public:
  SlopeChange() : SemiExplicitSystem({D}) {}
  EvalStatus equations(double, const Vector&, const Predicates& p, Vector& out) override {
    out[0] = p[0] ? 2.0 : 1.0;
    return EvalStatus::ok;
  }
  int predicate_count() const override { return 1; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = z[0];
    return EvalStatus::ok;
  }
};

Options precise() {
  Options options;
  options.rtol = 1e-9;
  options.atol = 1e-12;
  return options;
}

// x' = cos t, so x = sin t, and p = (x > 0.9999): true for 0.028 about t = pi / 2, a fraction
// of the steps sin t allows. The guard is negative at both ends of the step that crosses the
// window; the crossing and the return must still be found. x's global error there is a few tens
// of rtol, and the instants' that over the slope there, cos t = 0.014.
class BriefWindow : public SemiExplicitSystem {
 public:
  BriefWindow() : SemiExplicitSystem({D}) {}
  EvalStatus equations(double t, const Vector&, const Predicates&, Vector& out) override {
    out[0] = std::cos(t);
    return EvalStatus::ok;
  }
  static constexpr double kLevel = 0.9999;
  int predicate_count() const override { return 1; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = z[0] - kLevel;
    return EvalStatus::ok;
  }
};

TEST(Events, AGuardThatCrossesAndComesBackInsideOneStepIsFound) {
  for (double rtol : {1e-4, 1e-5, 1e-6}) {
    BriefWindow model;
    Options options;
    options.rtol = rtol;
    options.atol = rtol;
    Integrator integrator(model, options);
    ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(1))) << integrator.failure().reason;
    std::vector<double> event_times;
    double longest_step = 0, previous = 0;
    ASSERT_TRUE(run_until(integrator, 3.0, [&](const StepOutcome& outcome) {
      if (outcome.kind == StepKind::event) event_times.push_back(outcome.t);
      longest_step = std::max(longest_step, outcome.t - previous);
      previous = outcome.t;
    })) << integrator.failure().reason;
    const double enter = std::asin(BriefWindow::kLevel), leave = std::numbers::pi - enter;
    EXPECT_GT(longest_step, 2 * (leave - enter)) << "rtol " << rtol;
    ASSERT_EQ(event_times.size(), 2u) << "rtol " << rtol;
    const double resolution = 100 * rtol / std::cos(enter);
    EXPECT_NEAR(event_times[0], enter, resolution) << "rtol " << rtol;
    EXPECT_NEAR(event_times[1], leave, resolution) << "rtol " << rtol;
  }
}

TEST(Events, AnEventAtTheInitialTime) {
  // x(0) = 0 sits on the switching surface and the motion leaves it upward at once: the
  // predicate is true from t0 + 0 (settled while initializing, or as an event at t0).
  SlopeChange model;
  Integrator integrator(model, precise());
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(1))) << integrator.failure().reason;
  ASSERT_TRUE(run_until(integrator, 1.0, [&](const StepOutcome& outcome) {
    if (outcome.kind == StepKind::event) {
      EXPECT_LT(outcome.t, 1e-12);
    }
  })) << integrator.failure().reason;
  EXPECT_EQ(integrator.predicates()[0], 1);
  EXPECT_NEAR(integrator.state()[0], 2.0, 1e-9);
}

TEST(Events, AnEventInsideTheFirstStep) {
  SlopeChange model;
  Options options = precise();
  options.initial_step = 0.1;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, -1e-6))) << integrator.failure().reason;
  std::vector<double> event_times;
  ASSERT_TRUE(run_until(integrator, 1.0, [&](const StepOutcome& outcome) {
    if (outcome.kind == StepKind::event) event_times.push_back(outcome.t);
  })) << integrator.failure().reason;
  ASSERT_EQ(event_times.size(), 1u);
  // The root finder's bracket, 100 ulp of the step, is at most that wide: its right end is
  // within twice that of the root.
  EXPECT_NEAR(event_times[0], 1e-6, 2 * 100 * 2.2e-16 * 0.1);
  EXPECT_NEAR(integrator.state()[0], 2 * (1 - 1e-6), 1e-9);
}

// x' = 1 with p1 = (x > 0.5) and p2 = (t > 0.5): both change at t = 0.5, in one event.
class TwoAtOnce : public SemiExplicitSystem {
 public:
  TwoAtOnce() : SemiExplicitSystem({D}) {}
  EvalStatus equations(double, const Vector&, const Predicates&, Vector& out) override {
    out[0] = 1;
    return EvalStatus::ok;
  }
  int predicate_count() const override { return 2; }
  EvalStatus guards(double t, const Vector& z, Vector& out) const override {
    out[0] = z[0] - 0.5;
    out[1] = t - 0.5;
    return EvalStatus::ok;
  }
};

TEST(Events, SimultaneousEventsAreOneEvent) {
  TwoAtOnce model;
  Integrator integrator(model, precise());
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(1))) << integrator.failure().reason;
  std::vector<EventRecord> events;
  ASSERT_TRUE(run_until(integrator, 1.0, [&](const StepOutcome& outcome) {
    if (outcome.kind == StepKind::event) events.push_back(integrator.last_event());
  }));
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NEAR(events[0].t, 0.5, 2 * 100 * 2.2e-16 * 1.0);  // twice the bracket at t + h <= 1
  EXPECT_EQ(events[0].flips.size(), 2u);
  EXPECT_EQ(integrator.predicates(), (Predicates{1, 1}));
}

// x' = 1; p1 = (x > 1) makes the auxiliary y jump to 1; p2 = (y > 0.5) then holds too: the jump
// flips a further predicate, settled by the fixed point within the same event.
class Cascade : public SemiExplicitSystem {
 public:
  Cascade() : SemiExplicitSystem({D, X}) {}
  EvalStatus equations(double, const Vector&, const Predicates&, Vector& out) override {
    out[0] = 1;
    return EvalStatus::ok;
  }
  int predicate_count() const override { return 2; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = z[0] - 1;
    out[1] = z[1] - 0.5;
    return EvalStatus::ok;
  }
  bool has_jumps() const override { return true; }
  void jump_matrix(double, const Vector&, const Predicates&, std::vector<JumpEntry>& out) const override {
    out.push_back({1, 0, 1.0});
  }
};

TEST(Events, AJumpThatFlipsAFurtherPredicateSettlesInOneEvent) {
  Cascade model;
  Integrator integrator(model, precise());
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(2))) << integrator.failure().reason;
  std::vector<EventRecord> events;
  ASSERT_TRUE(run_until(integrator, 2.0, [&](const StepOutcome& outcome) {
    if (outcome.kind == StepKind::event) events.push_back(integrator.last_event());
  }));
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NEAR(events[0].t, 1.0, 1e-12);
  ASSERT_EQ(events[0].flips.size(), 2u);
  EXPECT_EQ(events[0].flips[0].predicate, 0);
  EXPECT_EQ(events[0].flips[1].predicate, 1);
  EXPECT_EQ(events[0].iterations, 2);
  EXPECT_EQ(integrator.state()[1], 1.0);
  EXPECT_NEAR(integrator.state()[0], 2.0, 1e-9);
}

// An ideal relay without hysteresis: x' = (p | -1 | 1), p = (x > 0). At x = 0 both modes point
// back across the switching surface (a sliding mode): the run must stop with a diagnostic. Each
// event settles in the mode its crossing leads to (a mode the fixed point left already is not
// re-entered), so the events accumulate at t = 1.
class Relay : public SemiExplicitSystem {
 public:
  Relay() : SemiExplicitSystem({D}) {}
  EvalStatus equations(double, const Vector&, const Predicates& p, Vector& out) override {
    out[0] = p[0] ? -1.0 : 1.0;
    return EvalStatus::ok;
  }
  int predicate_count() const override { return 1; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = z[0];
    return EvalStatus::ok;
  }
};

TEST(Events, ChatteringIsDiagnosedWithTimeAndPredicate) {
  Relay model;
  Integrator integrator(model, precise());
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, -1.0))) << integrator.failure().reason;
  EXPECT_FALSE(run_until(integrator, 3.0));
  EXPECT_NEAR(integrator.failure().t, 1.0, 1e-9);
  EXPECT_NE(integrator.failure().reason.find("chattering"), std::string::npos) << integrator.failure().reason;
  EXPECT_NE(integrator.failure().reason.find("predicate 0"), std::string::npos) << integrator.failure().reason;
}

// A gate drive read only by a guard: the algebraic g = z[1] = pulse(t), a trapezoid with corners
// at 1.1, 1.11, 1.13 and 1.14 (0 -> 1 -> 0), and p = (g > 0.5), on from 1.105 to 1.135. The
// corners are declared to enter row forcing_row; a model adds what p drives.
class GateDriven : public SemiExplicitSystem {
 public:
  GateDriven(std::vector<UnknownKind> kinds, std::vector<std::pair<int, int>> entries, int forcing_row)
      : SemiExplicitSystem(std::move(kinds), std::move(entries)), forcing_row_(forcing_row) {}
  int predicate_count() const override { return 1; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = z[1] - 0.5;
    return EvalStatus::ok;
  }
  double next_time_event(double t) const override {
    for (double corner : kCorners)
      if (corner > t) return corner;
    return std::numeric_limits<double>::infinity();
  }
  bool time_event_rows(double, std::vector<int>& rows) const override {
    rows.push_back(forcing_row_);
    return true;
  }
  static bool corner_between(double t_from, double t_to) {
    return std::any_of(std::begin(kCorners), std::end(kCorners),
                       [&](double corner) { return t_from < corner && corner < t_to; });
  }
  static double pulse(double t) {
    if (t <= 1.1 || t >= 1.14) return 0;
    if (t < 1.11) return (t - 1.1) / 0.01;
    return t <= 1.13 ? 1.0 : (1.14 - t) / 0.01;
  }

 private:
  static constexpr double kCorners[] = {1.1, 1.11, 1.13, 1.14};
  int forcing_row_;
};

// The counter x' = p, which runs from 1.105 to 1.135. g's row shares no block of the pattern
// with x, so its corners cannot bend the solution; with forcing_row = 0 the same corners are
// declared to enter x's row instead.
class GateDrivenCounter : public GateDriven {
 public:
  explicit GateDrivenCounter(int forcing_row) : GateDriven({D, A}, {{0, 0}, {1, 1}}, forcing_row) {}
  EvalStatus equations(double t, const Vector& z, const Predicates& p, Vector& out) override {
    out[0] = p[0] ? 1.0 : 0.0;
    out[1] = z[1] - pulse(t);
    return EvalStatus::ok;
  }
};

TEST(Events, StepsPassCornersThatCannotBendTheSolutionAndSampleTheGuardsThere) {
  for (int forcing_row : {1, 0}) {
    GateDrivenCounter model(forcing_row);
    Integrator integrator(model, precise());
    ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(2))) << integrator.failure().reason;
    std::vector<double> event_times;
    double longest_step = 0;
    ASSERT_TRUE(run_until(integrator, 2.0, [&](const StepOutcome& outcome) {
      if (outcome.kind == StepKind::event) event_times.push_back(outcome.t);
      longest_step = std::max(longest_step, integrator.step_size());
    })) << integrator.failure().reason;
    ASSERT_EQ(event_times.size(), 2u) << "forcing row " << forcing_row;
    EXPECT_NEAR(event_times[0], 1.105, 1e-12);
    EXPECT_NEAR(event_times[1], 1.135, 1e-12);
    EXPECT_NEAR(integrator.state()[0], 0.03, 1e-10);
    // Passed, a corner ends no step: a step spans the whole 40 ms pulse, found by the guards
    // sampled at its corners.
    EXPECT_EQ(integrator.statistics().time_events, forcing_row == 1 ? 0 : 4);
    if (forcing_row == 1) {
      EXPECT_GT(longest_step, 0.5);
    }
  }
}

// x' = -x beside a clock that nothing reads: g = z[1] = 0, with a corner every microsecond
// declared to enter g's row alone, a million of them by t = 1.
class UnreadClock : public SemiExplicitSystem {
 public:
  static constexpr double kPeriod = 1e-6;
  UnreadClock() : SemiExplicitSystem({D, A}, {{0, 0}, {1, 1}}) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = -z[0];
    out[1] = z[1];
    return EvalStatus::ok;
  }
  double next_time_event(double t) const override {
    double corner = (std::floor(t / kPeriod) + 1) * kPeriod;
    return corner > t ? corner : corner + kPeriod;
  }
  bool time_event_rows(double, std::vector<int>& rows) const override {
    rows.push_back(1);
    return true;
  }
};

TEST(Events, AStepPassesAtMostAThousandCorners) {
  // Its work bounded: a step over astronomically many corners would not end (and a run stays
  // interruptible between steps). The steps stay long all the same.
  UnreadClock model;
  Integrator integrator(model, precise());
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Unit(2, 0))) << integrator.failure().reason;
  double longest_step = 0;
  ASSERT_TRUE(run_until(integrator, 1.0, [&](const StepOutcome&) { longest_step = std::max(longest_step, integrator.step_size()); }))
      << integrator.failure().reason;
  EXPECT_LE(longest_step, 1000 * UnreadClock::kPeriod * (1 + 1e-9));
  EXPECT_GE(longest_step, 999 * UnreadClock::kPeriod);
  EXPECT_NEAR(integrator.state()[0], std::exp(-1.0), 1e-8);
  EXPECT_EQ(integrator.statistics().time_events, 0);
}

// The same drive gating a decay: x' = p - x / 10 from x = 1, y = z[2] = 2 x. Closed form:
// x = e^(-t/10), then relaxing towards 10 while p holds, from 1.105 to 1.135.
class GatedDecay : public GateDriven {
 public:
  GatedDecay() : GateDriven({D, A, A}, {{0, 0}, {1, 1}, {2, 0}, {2, 2}}, 1) {}
  EvalStatus equations(double t, const Vector& z, const Predicates& p, Vector& out) override {
    out[0] = (p[0] ? 1.0 : 0.0) - z[0] / 10;
    out[1] = z[1] - pulse(t);
    out[2] = z[2] - 2 * z[0];
    return EvalStatus::ok;
  }
  static double exact_x(double t) {
    constexpr double kOn = 1.105, kOff = 1.135;
    const double at_on = std::exp(-kOn / 10);
    auto relaxing = [&](double s) { return 10 + (at_on - 10) * std::exp(-(s - kOn) / 10); };
    if (t <= kOn) return std::exp(-t / 10);
    if (t <= kOff) return relaxing(t);
    return relaxing(kOff) * std::exp(-(t - kOff) / 10);
  }
};

// A corner the step passed reaches only its own block of the pattern: rows of g inside such a
// step are solved (g's polynomial cannot bend at the corners), rows of y (algebraic, but in x's
// block) are the step's polynomial, as in any step.
TEST(Events, DenseOutputSolvesOnlyTheUnknownsAPassedCornerReaches) {
  GatedDecay model;
  Options options;
  options.rtol = 1e-6;
  options.atol = 1e-9;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{1.0, 0.0, 2.0}})) << integrator.failure().reason;
  const std::vector<int> only_g{1}, only_y{2};
  int rows_past_corners = 0;
  double worst_g = 0, worst_g_polynomial = 0, worst_y = 0;
  double t_before = 0;
  ASSERT_TRUE(run_until(integrator, 2.0, [&](const StepOutcome& outcome) {
    const bool passed_corner = GatedDecay::corner_between(t_before, outcome.t);
    for (double fraction : {0.1, 0.3, 0.5, 0.7, 0.9}) {
      const double t_at = t_before + fraction * (outcome.t - t_before);
      const double g = integrator.dense_output(t_at, only_g)[1];
      const double y = integrator.dense_output(t_at, only_y)[2];
      worst_y = std::max(worst_y, std::abs(y - 2 * GatedDecay::exact_x(t_at)));
      if (!passed_corner) continue;
      ++rows_past_corners;
      worst_g = std::max(worst_g, std::abs(g - GatedDecay::pulse(t_at)));
      worst_g_polynomial = std::max(worst_g_polynomial, std::abs(integrator.interpolate(t_at)[1] - GatedDecay::pulse(t_at)));
      EXPECT_EQ(y, integrator.interpolate(t_at)[2]) << "t = " << t_at;
    }
    t_before = outcome.t;
  })) << integrator.failure().reason;
  EXPECT_GE(rows_past_corners, 10);
  EXPECT_GT(worst_g_polynomial, 0.1);  // the case the test is about
  EXPECT_LT(worst_g, 1e-9);
  EXPECT_LT(worst_y, 1e-5);  // global error: a few tolerances of y's scale
}

// Without predicates no guard is ever evaluated; without jumps no jump matrix is asked for.
class Counting : public SemiExplicitSystem {
 public:
  Counting() : SemiExplicitSystem({D}) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = -z[0];
    return EvalStatus::ok;
  }
  EvalStatus guards(double, const Vector&, Vector&) const override {
    ++guard_calls;
    return EvalStatus::ok;
  }
  void jump_matrix(double, const Vector&, const Predicates&, std::vector<JumpEntry>&) const override {
    ++jump_calls;
  }
  mutable int guard_calls = 0, jump_calls = 0;
};

TEST(Events, ACircuitPaysOnlyForWhatItUses) {
  Counting model;
  Integrator integrator(model, precise());
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0)));
  ASSERT_TRUE(run_until(integrator, 5.0));
  EXPECT_EQ(model.guard_calls, 0);
  EXPECT_EQ(model.jump_calls, 0);
  EXPECT_EQ(integrator.statistics().events, 0);
}

// x' = p - x, p = (t < 1): affine in x in both modes, x = 1 - e^-t, then (1 - e^-1) e^-(t - 1).
class SwitchedRelaxation : public SemiExplicitSystem {
 public:
  explicit SwitchedRelaxation(bool claims_constant_jacobian)
      : SemiExplicitSystem({D}), claims_constant_jacobian_(claims_constant_jacobian) {}
  EvalStatus equations(double, const Vector& z, const Predicates& p, Vector& out) override {
    out[0] = p[0] - z[0];
    return EvalStatus::ok;
  }
  bool constant_jacobian() const override { return claims_constant_jacobian_; }
  int predicate_count() const override { return 1; }
  EvalStatus guards(double t, const Vector&, Vector& out) const override {
    out[0] = 1 - t;
    return EvalStatus::ok;
  }

 private:
  bool claims_constant_jacobian_;
};

TEST(Events, AConstantJacobianIsLoadedOncePerModeAndSolver) {
  const double exact = (1 - std::exp(-1.0)) * std::exp(-1.0);
  long jacobians_loaded_anyway = 0;
  for (bool claimed : {false, true}) {
    SwitchedRelaxation model(claimed);
    Integrator integrator(model, precise());
    ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(1))) << integrator.failure().reason;
    ASSERT_TRUE(run_until(integrator, 2.0)) << integrator.failure().reason;
    EXPECT_NEAR(integrator.state()[0], exact, 1e-8);
    EXPECT_EQ(integrator.statistics().events, 1);
    if (!claimed) {
      jacobians_loaded_anyway = integrator.statistics().jacobians;
      continue;
    }
    // Two modes, two solvers that load derivatives (the steps' and the event locator's).
    EXPECT_LE(integrator.statistics().jacobians, 4);
    EXPECT_GT(jacobians_loaded_anyway, 20);  // what the claim saves
  }
}

// x'' = -x for x > 0 and x'' = -4 x for x < 0: half periods of pi and pi/2, and |x'| = 1 at
// every crossing of x = 0 (the potential is zero there on both sides). Started at x = sin 0.5,
// x' = cos 0.5: downward crossings at pi - 0.5 + k 3pi/2, upward ones pi/2 later.
class StiffeningOscillator : public SemiExplicitSystem {
 public:
  StiffeningOscillator() : SemiExplicitSystem({D, D}) {}
  EvalStatus equations(double, const Vector& z, const Predicates& p, Vector& out) override {
    out[0] = z[1];
    out[1] = -(p[0] ? 1.0 : 4.0) * z[0];
    return EvalStatus::ok;
  }
  int predicate_count() const override { return 1; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = z[0];
    return EvalStatus::ok;
  }
};

// The trapezoidal method restarts after each event like BDF does, with two backward-Euler steps,
// each within the tolerance. Over 100 cycles the crossing times drift by no more than the local
// errors add up to (steps x rtol; the phase error of the trapezoidal rule) and |x'| at the
// crossings by no more than those restarts lose (2 x rtol each).
TEST(Events, TrapezoidalLocatesEventsAndKeepsTheAmplitudeAcrossThem) {
  StiffeningOscillator model;
  Options options;
  options.method = Method::trapezoidal;
  options.rtol = 1e-7;
  options.atol = 1e-10;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{std::sin(0.5), std::cos(0.5)}})) << integrator.failure().reason;
  const double pi = std::numbers::pi;
  int crossings = 0;
  double worst_time = 0, worst_speed = 0;
  ASSERT_TRUE(run_until(integrator, 100 * 1.5 * pi, [&](const StepOutcome& outcome) {
    if (outcome.kind != StepKind::event) return;
    const double exact = pi - 0.5 + (crossings / 2) * 1.5 * pi + (crossings % 2) * 0.5 * pi;
    worst_time = std::max(worst_time, std::abs(outcome.t - exact));
    worst_speed = std::max(worst_speed, std::abs(std::abs(integrator.state()[1]) - 1));
    ++crossings;
  })) << integrator.failure().reason;
  EXPECT_EQ(crossings, 200);
  EXPECT_LT(worst_time, static_cast<double>(integrator.statistics().steps) * options.rtol);
  EXPECT_LT(worst_speed, 2 * crossings * options.rtol);
}

// A half-bridge's high side on a split DC bus: a 380 V source across C1 (p to m) and C2 (m to
// ground); a switch of conductance G from p to the switch node s, which has Cs to ground and R to
// the midpoint m. The source's current i = C1 v_m' - G (E - v_s) is index 2: in a step of length h
// one ulp of v_m moves it by C1 / h ulp. Between events the circuit is linear, y = (v_m, v_s),
// y' = M y + c, and solved in closed form by the eigen-decomposition of M.
class SplitBus : public System {
 public:
  static constexpr double kE = 380, kC1 = 10e-6, kC2 = 10e-6, kCs = 300e-12, kR = 11, kG = 5, kT1 = 0.2e-6, kT2 = 5e-6, kRamp = 10e-9;
  int size() const override { return 4; }  // v_p, v_m, v_s, i
  UnknownKind kind(int unknown) const override { return unknown == 3 ? A : D; }
  const Pattern& pattern() const override { return pattern_; }
  int predicate_count() const override { return 1; }
  // A gate drive that ramps up over kRamp from kT1 and down from kT2; the switch follows it
  // at half way.
  EvalStatus guards(double t, const Vector&, Vector& out) const override {
    out[0] = std::clamp((t - kT1) / kRamp, 0.0, 1.0) - std::clamp((t - kT2) / kRamp, 0.0, 1.0) - 0.5;
    return EvalStatus::ok;
  }
  double next_time_event(double t) const override {
    for (double corner : {kT1, kT1 + kRamp, kT2, kT2 + kRamp})
      if (t < corner) return corner;
    return std::numeric_limits<double>::infinity();
  }
  EvalStatus load(double, const Vector& x, const Predicates& p, Load& out) override {
    const double g = p[0] ? kG : 0.0;
    out.q[0] = kC1 * (x[0] - x[1]);
    out.q[1] = kC1 * (x[1] - x[0]) + kC2 * x[1];
    out.q[2] = kCs * x[2];
    out.f[0] = x[3] + g * (x[0] - x[2]);
    out.f[1] = (x[1] - x[2]) / kR;
    out.f[2] = (x[2] - x[1]) / kR + g * (x[2] - x[0]);
    out.f[3] = x[0] - kE;
    if (!out.jacobian_requested) return EvalStatus::ok;
    auto at = [&](int row, int column) { return static_cast<std::size_t>(pattern_.index(row, column)); };
    out.dq_dx[at(0, 0)] = kC1;
    out.dq_dx[at(0, 1)] = -kC1;
    out.dq_dx[at(1, 0)] = -kC1;
    out.dq_dx[at(1, 1)] = kC1 + kC2;
    out.dq_dx[at(2, 2)] = kCs;
    out.df_dx[at(0, 0)] = g;
    out.df_dx[at(0, 2)] = -g;
    out.df_dx[at(0, 3)] = 1;
    out.df_dx[at(1, 1)] = 1 / kR;
    out.df_dx[at(1, 2)] = -1 / kR;
    out.df_dx[at(2, 0)] = -g;
    out.df_dx[at(2, 1)] = -1 / kR;
    out.df_dx[at(2, 2)] = 1 / kR + g;
    out.df_dx[at(3, 0)] = 1;
    return EvalStatus::ok;
  }
  // (v_m, v_s) a time `since` after the switch was set to `closed` at (v_m, v_s) = from.
  static Eigen::Vector2d exact(bool closed, const Eigen::Vector2d& from, double since) {
    const double g = closed ? kG : 0.0, a = 1 / (kR * (kC1 + kC2)), b = 1 / (kR * kCs);
    Eigen::Matrix2d m{{-a, a}, {b, -b - g / kCs}};
    const Eigen::Vector2d c{0, g * kE / kCs};
    // Open, M is singular: the charge (C1 + C2) v_m + Cs v_s is conserved and shared.
    const double shared = ((kC1 + kC2) * from[0] + kCs * from[1]) / (kC1 + kC2 + kCs);
    const Eigen::Vector2d equilibrium = closed ? Eigen::Vector2d(-m.inverse() * c) : Eigen::Vector2d(shared, shared);
    Eigen::EigenSolver<Eigen::Matrix2d> eigen(m);
    const Eigen::Matrix2d vectors = eigen.eigenvectors().real();
    const Eigen::Vector2d values = eigen.eigenvalues().real();
    const Eigen::Vector2d weights = vectors.inverse() * (from - equilibrium);
    return equilibrium + vectors * (weights.array() * (values.array() * since).exp()).matrix();
  }
  // The source's current at (v_m, v_s).
  static double current(bool closed, const Eigen::Vector2d& y) {
    const double v_m_derivative = (y[1] - y[0]) / (kR * (kC1 + kC2));
    return kC1 * v_m_derivative - (closed ? kG : 0.0) * (kE - y[1]);
  }

 private:
  static constexpr std::pair<int, int> kEntries[] = {{0, 0}, {0, 1}, {0, 2}, {0, 3}, {1, 0}, {1, 1},
                                                     {1, 2}, {2, 0}, {2, 1}, {2, 2}, {3, 0}};
  Pattern pattern_{4, kEntries};
};

// Across both edges of the switch, at tolerances down to 1e-9, the bus and the switch node
// follow the closed form, and so does the source's current once the 3 ns mode has settled.
TEST(Events, ASourceInALoopOfCapacitorsFollowsTheClosedFormAtTightTolerances) {
  for (double rtol : {1e-6, 1e-9}) {
    SplitBus model;
    Options options;
    options.rtol = rtol;
    options.atol = 1e-12;
    Integrator integrator(model, options);
    ASSERT_TRUE(integrator.initialize(0.0, Vector{{380, 190, 190, 0}})) << integrator.failure().reason;
    // The closed form runs from each located event and the state there: the root finder's
    // 100 ulp of a step are picoseconds' worth of v_s's slew.
    double t_event = 0, worst_v = 0, worst_i = 0;
    Eigen::Vector2d at_event = Eigen::Vector2d::Zero();
    bool closed = false;
    ASSERT_TRUE(run_until(integrator, 20e-6, [&](const StepOutcome& outcome) {
      const Vector& x = integrator.state();
      if (outcome.kind == StepKind::event) {
        t_event = outcome.t, closed = integrator.predicates()[0], at_event = {x[1], x[2]};
        return;
      }
      if (t_event == 0) return;
      const Eigen::Vector2d exact = SplitBus::exact(closed, at_event, outcome.t - t_event);
      worst_v = std::max({worst_v, std::abs(x[1] - exact[0]), std::abs(x[2] - exact[1])});
      // After the 3 ns mode has died out, in units of the current while the switch conducts
      // (E / 2 through R, C1's share); the current is v_m's derivative, one order less accurate
      // than v_m.
      const double scale = SplitBus::kC1 / (SplitBus::kC1 + SplitBus::kC2) * SplitBus::kE / 2 / SplitBus::kR;
      if (outcome.t > t_event + 30e-9) worst_i = std::max(worst_i, std::abs(x[3] - SplitBus::current(closed, exact)) / scale);
    })) << "rtol " << rtol << ": " << integrator.failure().reason;
    EXPECT_LT(worst_v, 10 * rtol * SplitBus::kE) << "rtol " << rtol;
    EXPECT_LT(worst_i, 100 * rtol) << "rtol " << rtol;
  }
}

// IDA's error weights, 1 / (rtol |x| + atol): within_roundoff() measures corrections in them.
Vector inverse_error_weight(const Vector& x, double rtol, double atol) {
  return (rtol * x.cwiseAbs() + Vector::Constant(x.size(), atol)).cwiseInverse();
}

// In a step of h = 1 ps, one ulp of v_m (190 V) is C1 / h ulp = 2.8e-7 A of the source's current
// i = -8.3 A, 34 times its tolerance at rtol 1e-9. A correction of that size in i is the residual's
// rounding; one a thousand times larger is not, nor is a correction beyond the tolerance in a
// differential unknown that moves the charges (they are always resolved to their tolerance).
TEST(NewtonMatrix, RoundOffAllowanceCoversAnIndexTwoCurrentsUlpNoiseOnly) {
  SplitBus model;
  Statistics statistics;
  NewtonMatrix newton(model, statistics, Vector::Constant(4, 1e-12));
  const Vector x{{380, 190, 190, -8.3}};
  const double rtol = 1e-9, cj = 1e12;
  ASSERT_EQ(newton.factor(0, x, {0}, cj), NewtonMatrix::Outcome::ok);
  const Vector q_start = newton.load().q;
  const Vector inverse_weight = inverse_error_weight(x, rtol, 1e-12);
  const double ulp_current = SplitBus::kC1 * cj * (std::nextafter(190.0, 400.0) - 190.0);
  auto within = [&](int unknown, double correction) {
    Vector delta = Vector::Zero(4);
    delta[unknown] = correction;
    return newton.within_roundoff(delta, 1, inverse_weight, 1, x, cj * q_start);
  };
  EXPECT_GT(ulp_current, 30 / inverse_weight[3]);
  EXPECT_TRUE(within(3, ulp_current));
  EXPECT_TRUE(within(3, -ulp_current));
  EXPECT_FALSE(within(3, 1e3 * ulp_current));
  EXPECT_TRUE(within(1, 0.9 / inverse_weight[1]));
  EXPECT_FALSE(within(1, 2 / inverse_weight[1]));
}

// Two differential unknowns, every entry of the 2 x 2 Jacobians in the pattern.
class TwoDifferentialUnknowns : public System {
 public:
  int size() const override { return 2; }
  UnknownKind kind(int) const override { return D; }
  const Pattern& pattern() const override { return pattern_; }

 protected:
  std::size_t at(int row, int column) const { return static_cast<std::size_t>(pattern_.index(row, column)); }

 private:
  static constexpr std::pair<int, int> kEntries[] = {{0, 0}, {0, 1}, {1, 0}, {1, 1}};
  Pattern pattern_{2, kEntries};
};

// A capacitor C between nodes a and b, each tied to ground by G only (a floating secondary's
// 1 MOhm): the pair's common mode is algebraic, and in a short step C / h swamps G in both rows.
// Rounding then leaves the common mode resolved to about eps (C / h) |v| / G, not to the
// tolerance: a correction of that size along it moves no charge and is the residual's noise,
// while one across the capacitor is not. Where eps C / h exceeds G nothing resolves the
// common mode any more, and no correction along it is noise.
class FloatingCapacitor : public TwoDifferentialUnknowns {
 public:
  static constexpr double kC = 1e-6, kG = 1e-6, kI = 1e-3;
  EvalStatus load(double, const Vector& x, const Predicates&, Load& out) override {
    out.q[0] = kC * (x[0] - x[1]);
    out.q[1] = -out.q[0];
    out.f[0] = kG * x[0] - kI;
    out.f[1] = kG * x[1];
    if (!out.jacobian_requested) return EvalStatus::ok;
    out.dq_dx[at(0, 0)] = out.dq_dx[at(1, 1)] = kC;
    out.dq_dx[at(0, 1)] = out.dq_dx[at(1, 0)] = -kC;
    out.df_dx[at(0, 0)] = out.df_dx[at(1, 1)] = kG;
    return EvalStatus::ok;
  }
};

TEST(NewtonMatrix, RoundOffAllowanceCoversAFloatingCapacitorsCommonModeWhereRoundingResolvesIt) {
  FloatingCapacitor model;
  Statistics statistics;
  NewtonMatrix newton(model, statistics, Vector::Constant(2, 1e-9));
  const Vector x{{500, 400}};
  const double rtol = 1e-6;
  const Vector inverse_weight = inverse_error_weight(x, rtol, 1e-9);
  const double tolerance = 1 / inverse_weight[1];  // 4e-4 V
  auto within = [&](double cj, double common, double across) {
    EXPECT_EQ(newton.factor(0, x, {}, cj), NewtonMatrix::Outcome::ok);
    const Vector delta{{common + across / 2, common - across / 2}};
    return newton.within_roundoff(delta, 1, inverse_weight, 1, x, Vector::Zero(2));
  };
  // h = 1 ns: eps (C / h) |v| / G = 2e-4 V, within the tolerance.
  EXPECT_FALSE(within(1e9, 3 * tolerance, 0));
  // h = 1 ps: 0.2 V, 500 tolerances.
  EXPECT_TRUE(within(1e12, 0.1, 0));
  EXPECT_FALSE(within(1e12, 1, 0));
  EXPECT_FALSE(within(1e12, 0, 3 * tolerance));
  // h = 1 fs: eps C / h = 0.2 G.
  EXPECT_FALSE(within(1e15, 3 * tolerance, 0));
}

// Two coupled inductors, k = 1 - 1e-8, in flux rows: q = -L [1 k; k 1] i, each across a
// source. Rows of equal size: rounding moves their difference mode (the leakage) by
// 2 eps |i| / (1 - k), 1e8 times what it moves their common mode by.
class TightlyCoupledInductors : public TwoDifferentialUnknowns {
 public:
  static constexpr double kL = 1e-3, kK = 1 - 1e-8, kV = 1;
  EvalStatus load(double, const Vector& x, const Predicates&, Load& out) override {
    out.q[0] = -kL * (x[0] + kK * x[1]);
    out.q[1] = -kL * (kK * x[0] + x[1]);
    out.f[0] = out.f[1] = kV;
    if (!out.jacobian_requested) return EvalStatus::ok;
    out.dq_dx[at(0, 0)] = out.dq_dx[at(1, 1)] = -kL;
    out.dq_dx[at(0, 1)] = out.dq_dx[at(1, 0)] = -kL * kK;
    return EvalStatus::ok;
  }
};

TEST(NewtonMatrix, RoundOffAllowanceSeesTheLeakageModeOfSymmetricRows) {
  TightlyCoupledInductors model;
  Statistics statistics;
  NewtonMatrix newton(model, statistics, Vector::Constant(2, 1e-12));
  const Vector x{{50, 50}};
  const double rtol = 1e-9;
  const Vector inverse_weight = inverse_error_weight(x, rtol, 1e-12);
  const double tolerance = 1 / inverse_weight[0];  // 5e-8 A
  ASSERT_EQ(newton.factor(0, x, {}, 1e10), NewtonMatrix::Outcome::ok);
  // 2 eps |i| / (1 - k) = 2.2e-6 A: a leakage correction of a few tolerances is rounding (rows 0
  // and 1 have the same sign in one of the two patterns); one of a thousand is not.
  auto within = [&](double leakage) {
    return newton.within_roundoff(Vector{{leakage, -leakage}}, 1, inverse_weight, 1, x, Vector::Zero(2));
  };
  EXPECT_TRUE(within(3 * tolerance));
  EXPECT_FALSE(within(1000 * tolerance));
}

}  // namespace
}  // namespace padae
