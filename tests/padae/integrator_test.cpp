#include "padae/integrator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "padae/newton_matrix.hpp"
#include "padae/semi_explicit.hpp"
#include "padae/steady_state.hpp"
#include "padae/subnormals.hpp"
#include "run_until.hpp"

namespace padae {
namespace {

using testing::run_until;
constexpr auto D = UnknownKind::differential;
constexpr auto A = UnknownKind::algebraic;

// x' = -lambda x: the plainest check of order, step control and accuracy.
class Decay : public SemiExplicitSystem {
 public:
  explicit Decay(double lambda) : SemiExplicitSystem({D}), lambda_(lambda) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = -lambda_ * z[0];
    return EvalStatus::ok;
  }

 private:
  double lambda_;
};

TEST(Integrator, DecayIsAccurateToTheToleranceAndConvergesAsItTightens) {
  double previous_error = 1;
  for (double rtol : {1e-4, 1e-6, 1e-8, 1e-10}) {
    Decay decay(3.0);
    Options options;
    options.rtol = rtol;
    options.atol = rtol * 1e-3;
    Integrator integrator(decay, options);
    ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0))) << integrator.failure().reason;
    ASSERT_TRUE(run_until(integrator, 2.0));
    double error = std::abs(integrator.state()[0] - std::exp(-6.0)) / std::exp(-6.0);
    EXPECT_LT(error, 100 * rtol) << "rtol " << rtol;
    EXPECT_LT(error, previous_error);
    previous_error = error;
    EXPECT_EQ(integrator.time(), 2.0);  // t_stop is hit exactly
  }
}

TEST(Integrator, StopWithinTheTimeResolutionIsReachedWithoutAStep) {
  // A source corner computed as 200 * 1e-6 lies an ulp before TSTOP = 2e-4: the step left is
  // shorter than the time resolution, and the state there is the state at TSTOP.
  Decay decay(3.0);
  Integrator integrator(decay, Options{});
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0))) << integrator.failure().reason;
  const double corner = 200 * 1e-6, t_stop = 2e-4;
  ASSERT_LT(corner, t_stop);
  ASSERT_TRUE(run_until(integrator, corner));
  const double x_at_corner = integrator.state()[0];
  const long steps = integrator.statistics().steps;
  const StepOutcome outcome = integrator.step(t_stop);
  EXPECT_EQ(outcome.kind, StepKind::stop);
  EXPECT_EQ(integrator.time(), t_stop);
  EXPECT_EQ(integrator.state()[0], x_at_corner);
  EXPECT_EQ(integrator.statistics().steps, steps);
}

TEST(Integrator, TransientFasterThanTheTimeResolutionIsPassedOverAndReported) {
  // At t = 0.1 s no step below 16 ulp of t (3.6e-16 s) advances t; a decay of 1e-16 s fails
  // the error test at every step that does. Its end state (x = 0) is reached all the same.
  Decay decay(1e16);
  Integrator integrator(decay, Options{});
  ASSERT_TRUE(integrator.initialize(0.1, Vector::Constant(1, 1.0))) << integrator.failure().reason;
  ASSERT_TRUE(run_until(integrator, 0.2)) << integrator.failure().reason;
  EXPECT_LT(std::abs(integrator.state()[0]), 1e-12);
  EXPECT_GT(integrator.statistics().unresolved_steps, 0);
  ASSERT_TRUE(integrator.unresolved_transient().has_value());
  EXPECT_EQ(integrator.unresolved_transient()->t, 0.1);
  EXPECT_EQ(integrator.unresolved_transient()->unknown, 0);
  EXPECT_NEAR(integrator.unresolved_transient()->resolution, 16 * std::numeric_limits<double>::epsilon() * 0.1, 1e-30);

  // A growth as fast, which backward Euler at that step would damp as well, stops the run.
  Decay growth(-1e16);
  Integrator growing(growth, Options{});
  ASSERT_TRUE(growing.initialize(0.1, Vector::Constant(1, 1.0))) << growing.failure().reason;
  EXPECT_FALSE(run_until(growing, 0.2));
  EXPECT_EQ(growing.statistics().unresolved_steps, 0);

  // Where the step resolves the decay nothing is passed over.
  Decay resolvable(1e16);
  Integrator early(resolvable, Options{});
  ASSERT_TRUE(early.initialize(1e-6, Vector::Constant(1, 1.0))) << early.failure().reason;
  ASSERT_TRUE(run_until(early, 2e-6)) << early.failure().reason;
  EXPECT_EQ(early.statistics().unresolved_steps, 0);
}

// x'' = -x as a first-order system: the step-size and order controller must reach high order.
class Oscillator : public SemiExplicitSystem {
 public:
  Oscillator() : SemiExplicitSystem({D, D}) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = z[1];
    out[1] = -z[0];
    return EvalStatus::ok;
  }
  bool has_equation_jacobian() const override { return true; }
  bool equation_jacobian(double, const Vector&, const Predicates&, std::vector<double>& values) override {
    values[pattern().index(0, 1)] = 1;
    values[pattern().index(1, 0)] = -1;
    return true;
  }
};

TEST(Integrator, OscillatorOverTenPeriodsReachesHighOrder) {
  Oscillator oscillator;
  Options options;
  options.rtol = 1e-8;
  options.atol = 1e-10;
  Integrator integrator(oscillator, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Unit(2, 0))) << integrator.failure().reason;
  int highest_order = 0;
  const double t_end = 20 * std::numbers::pi;
  ASSERT_TRUE(run_until(integrator, t_end, [&](const StepOutcome&) {
    highest_order = std::max(highest_order, integrator.order());
  }));
  EXPECT_NEAR(integrator.state()[0], 1.0, 1e-5);
  EXPECT_NEAR(integrator.state()[1], 0.0, 1e-5);
  EXPECT_GE(highest_order, 4);
  EXPECT_LT(integrator.statistics().steps, 3000);
}

// Options::peak_floor: with an absolute tolerance far below the signal (1e-30 beside a start of
// 1), rtol |x| + atol holds a decay's tail to rtol of itself however small it gets, a step per
// fraction of the time constant for ever. With the floor, rtol applies to at least 1e-3 of the
// peak: the error against e^-t, relative to the peak, stays at the tolerance, and once the tail
// is below the floor the steps grow.
TEST(Integrator, PeakFloorKeepsTheErrorRelativeToThePeakWithFewerSteps) {
  long steps[2] = {0, 0};
  const double floors[2] = {0.0, 1e-3};
  for (int k = 0; k < 2; ++k) {
    Decay decay(1.0);
    Options options;
    options.rtol = 1e-6;
    options.atol = 1e-30;
    options.peak_floor = floors[k];
    Integrator integrator(decay, options);
    ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0))) << integrator.failure().reason;
    double worst = 0;
    ASSERT_TRUE(run_until(integrator, 100.0, [&](const StepOutcome&) {
      worst = std::max(worst, std::abs(integrator.state()[0] - std::exp(-integrator.time())));
    }));
    EXPECT_LT(worst, 10 * options.rtol) << "peak_floor " << floors[k];
    steps[k] = integrator.statistics().steps;
  }
  EXPECT_LT(steps[1], 0.5 * steps[0]) << steps[0] << " steps without the floor, " << steps[1] << " with it";
}

// y' = -cbrt(y), y(0) = 1: y = (1 - 2t/3)^(3/2) until t* = 3/2. Its k-th derivative grows like
// (t* - t)^(3/2 - k) towards t*, as a junction's voltage does where its current falls to zero
// (boost.cir in discontinuous conduction). A step rule that looks only at the last error keeps
// the step until the error test fails; predicting the error's growth from the last two steps
// cuts it before (over this sweep: 134 of 1,346 attempts failed without the prediction, 56 of
// 1,312 with it).
class CubeRootDecay : public SemiExplicitSystem {
 public:
  CubeRootDecay() : SemiExplicitSystem({D}) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = -std::cbrt(z[0]);
    return EvalStatus::ok;
  }
};

TEST(Integrator, ApproachingAGrowingDerivativeTheErrorTestRarelyFails) {
  long attempts = 0, failed = 0;
  for (double rtol : {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9}) {
    CubeRootDecay system;
    Options options;
    options.rtol = rtol;
    options.atol = 1e-12;
    Integrator integrator(system, options);
    ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0))) << integrator.failure().reason;
    double worst = 0;
    ASSERT_TRUE(run_until(integrator, 1.5, [&](const StepOutcome&) {
      const double exact = std::pow(std::max(1 - 2 * integrator.time() / 3, 0.0), 1.5);
      worst = std::max(worst, std::abs(integrator.state()[0] - exact));
    })) << integrator.failure().reason;
    EXPECT_LT(worst, 10 * rtol) << "rtol " << rtol;
    const Statistics& statistics = integrator.statistics();
    attempts += statistics.steps + statistics.rejected_error_test;
    failed += statistics.rejected_error_test;
  }
  EXPECT_LT(failed, attempts / 15) << failed << " of " << attempts << " attempts failed the error test";
}

// An rtol below double precision is raised to kSmallestRtol: the error test at rtol 1e-17 could
// pass only by the chance of its round-off, and the steps would shrink without end. The decay
// then runs to its end in a bounded number of steps, as close to e^-t as kSmallestRtol allows.
TEST(Integrator, RtolBelowDoublePrecisionIsRaisedToTheSmallestThatResolves) {
  Decay decay(1.0);
  Options options;
  options.rtol = 1e-17;
  options.atol = 1e-30;
  Integrator integrator(decay, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0))) << integrator.failure().reason;
  constexpr long kStepBudget = 100000;
  double worst = 0;
  while (integrator.time() < 5.0 && integrator.statistics().steps < kStepBudget) {
    ASSERT_NE(integrator.step(5.0).kind, StepKind::failed) << integrator.failure().reason;
    worst = std::max(worst, std::abs(integrator.state()[0] - std::exp(-integrator.time())));
  }
  EXPECT_EQ(integrator.time(), 5.0) << integrator.statistics().steps << " steps";
  EXPECT_LT(worst, 1e-13);
}

// x' = -x beside 0 = (y + 10)^2 - (g + 10)^2, g = 10 e^(-10 t): the root y = g falls from 10 to
// nothing, and the squares round to ulps of 100, while the absolute tolerance is 1e-17. The run
// must go on, y on its root within rtol of its peak. (Newton happens to land on exact roots of
// the rounded squares here, with or without the round-off floor on its tolerance: the floor's
// own test is the robustness case tolerance_below_roundoff_junctions.)
class RoundedRoot : public SemiExplicitSystem {
 public:
  RoundedRoot() : SemiExplicitSystem({D, A}, {{0, 0}, {1, 1}}) {}
  static double root(double t) { return 10 * std::exp(-10 * t); }
  EvalStatus equations(double t, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = -z[0];
    const double shifted = root(t) + 10;
    out[1] = (z[1] + 10) * (z[1] + 10) - shifted * shifted;
    return EvalStatus::ok;
  }
};

TEST(Integrator, AbsoluteToleranceBelowRoundOffKeepsTheRunOnTheRoot) {
  RoundedRoot model;
  Options options;
  options.rtol = 1e-12;
  options.atol = 1e-17;
  Integrator integrator(model, options);
  Vector start(2);
  start << 1, RoundedRoot::root(0);
  ASSERT_TRUE(integrator.initialize(0.0, start)) << integrator.failure().reason;
  double worst = 0;
  EXPECT_TRUE(run_until(integrator, 10.0, [&](const StepOutcome&) {
    worst = std::max(worst, std::abs(integrator.state()[1] - RoundedRoot::root(integrator.time())));
  })) << integrator.failure().reason;
  EXPECT_LT(worst, options.rtol * RoundedRoot::root(0));
}

// The trapezoidal rule is A-stable without damping: x'' = -x keeps its amplitude over 1,000
// periods at a loose tolerance, where BDF (its L-stable low orders) visibly damps it.
TEST(Integrator, TrapezoidalKeepsAnUndampedOscillationsAmplitude) {
  auto amplitude_after = [](Method method) {
    Oscillator oscillator;
    Options options;
    options.method = method;
    options.rtol = 1e-3;
    options.atol = 1e-6;
    Integrator integrator(oscillator, options);
    EXPECT_TRUE(integrator.initialize(0.0, Vector::Unit(2, 0))) << integrator.failure().reason;
    EXPECT_TRUE(run_until(integrator, 2000 * std::numbers::pi)) << integrator.failure().reason;
    return integrator.state().norm();
  };
  EXPECT_NEAR(amplitude_after(Method::trapezoidal), 1.0, 1e-6);
  EXPECT_LT(amplitude_after(Method::bdf), 1.0 - 1e-3);
}

// Second order: tightening the tolerance 1000-fold shrinks the global error about 1000^(2/3)
// = 100-fold (local error h^3 held to the tolerance, global error h^2). The local errors of a
// decay add up without decaying relative to x (each step's factor (1 + z/2) / (1 - z/2) misses
// e^z by z^3 / 12), so the relative global error is bounded by steps x rtol, not by rtol.
TEST(Integrator, TrapezoidalIsSecondOrderAndMeetsItsTolerance) {
  std::vector<double> errors;
  for (double rtol : {1e-4, 1e-7, 1e-10}) {
    Decay decay(3.0);
    Options options;
    options.method = Method::trapezoidal;
    options.rtol = rtol;
    options.atol = rtol * 1e-3;
    Integrator integrator(decay, options);
    ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0))) << integrator.failure().reason;
    ASSERT_TRUE(run_until(integrator, 2.0, [&](const StepOutcome&) { EXPECT_LE(integrator.order(), 2); }));
    errors.push_back(std::abs(integrator.state()[0] - std::exp(-6.0)) / std::exp(-6.0));
    EXPECT_LT(errors.back(), static_cast<double>(integrator.statistics().steps) * rtol) << "rtol " << rtol;
  }
  for (std::size_t k = 1; k < errors.size(); ++k) {
    EXPECT_GT(errors[k - 1] / errors[k], 30) << k;
    EXPECT_LT(errors[k - 1] / errors[k], 300) << k;
  }
}

TEST(Integrator, DenseOutputInterpolatesWithinTheStep) {
  Oscillator oscillator;
  Options options;
  options.rtol = 1e-9;
  options.atol = 1e-11;
  Integrator integrator(oscillator, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Unit(2, 0))) << integrator.failure().reason;
  double worst = 0;
  ASSERT_TRUE(run_until(integrator, 5.0, [&](const StepOutcome&) {
    double t_mid = integrator.time() - 0.5 * integrator.step_size();
    worst = std::max(worst, std::abs(integrator.interpolate(t_mid)[0] - std::cos(t_mid)));
  }));
  EXPECT_LT(worst, 1e-6);
}

// x' = 1e-6 y, 0 = y - sin(10 t): the steps follow x, which barely moves; y is not error-tested,
// so its interpolating polynomial is poor between steps (hundreds of y's tolerances), and dense
// output solves for it. Where the step's polynomial of y was within y's tolerance of the
// solution at the step's midpoint, the polynomial serves: dense output is then within y's
// tolerance, not round-off. Dense output of x alone (mostly the polynomial) stays as accurate as
// the steps.
class DrivenAlgebraic : public SemiExplicitSystem {
 public:
  DrivenAlgebraic() : SemiExplicitSystem({D, A}) {}
  EvalStatus equations(double t, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = 1e-6 * z[1];
    out[1] = z[1] - std::sin(10 * t);
    return EvalStatus::ok;
  }
};

TEST(Integrator, DenseOutputSolvesForTheAlgebraicUnknowns) {
  DrivenAlgebraic model;
  Options options;
  options.rtol = 1e-6;
  options.atol = 1e-9;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(2))) << integrator.failure().reason;
  double worst = 0, worst_polynomial = 0;  // in units of y's tolerance
  double worst_x = 0;
  const std::vector<int> only_x{0};
  ASSERT_TRUE(run_until(integrator, 2.0, [&](const StepOutcome&) {
    for (double fraction : {0.25, 0.5, 0.75}) {
      const double t_at = integrator.time() - fraction * integrator.step_size();
      const double exact = std::sin(10 * t_at), tolerance = options.rtol * std::abs(exact) + options.atol;
      worst = std::max(worst, std::abs(integrator.dense_output(t_at)[1] - exact) / tolerance);
      worst_polynomial = std::max(worst_polynomial, std::abs(integrator.interpolate(t_at)[1] - exact) / tolerance);
      worst_x = std::max(worst_x, std::abs(integrator.dense_output(t_at, only_x)[0] - 1e-7 * (1 - std::cos(10 * t_at))));
    }
  }));
  EXPECT_GT(worst_polynomial, 100);  // the case the test is about
  EXPECT_LE(worst, 1);
  EXPECT_LT(worst_x, 1e-8);  // ten absolute tolerances, as at the end
  EXPECT_NEAR(integrator.state()[0], 1e-7 * (1 - std::cos(20.0)), 1e-8);  // ten absolute tolerances
}

// An inductor from a source e(t) = -1 - sin(t) / 2 into a junction: L i' = e - v,
// 0 = i - IS (exp(v / VT) - 1). The inductor's initial current ramps down through the junction
// until it turns off (at about t = I0 L / 1.6); from then on it blocks, i stays at -IS and
// v = e to within L IS / VT. v is algebraic and flat in i there (dv/di = VT / (i + IS)):
// holding the interpolated i and solving for v would turn i's interpolation error into volts
// (padsim's flyback at default settings wrote -5002 V where the truth was 10 V).
class BlockingJunction : public SemiExplicitSystem {
 public:
  static constexpr double kInductance = 1e-3, kSaturation = 1e-9, kThermal = 0.025, kInitialCurrent = 1e-3;
  BlockingJunction() : SemiExplicitSystem({D, A}) {}
  static double source(double t) { return -1 - 0.5 * std::sin(t); }
  EvalStatus equations(double t, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = (source(t) - z[1]) / kInductance;
    out[1] = z[0] - kSaturation * std::expm1(z[1] / kThermal);
    return EvalStatus::ok;
  }
};

// Two RC circuits from E = 1 V. Node c: R3 to E, C2 to ground, v_c = 1 - exp(-t / (R3 C2)). Nodes
// a, b: R1 from E to a, C1 from a to b, R2 from b to ground; the capacitor's voltage
// u = v_a - v_b = 1 - exp(-t / tau), tau = C1 (R1 + R2), and v_b = R2 C1 u'. v_c is a function of
// its node's charge, so its polynomial is as good as the steps; v_a and v_b are not: each
// row's charge C1 u holds both, and v_b follows u', which the error test does not control.
class RcPair : public System {
 public:
  static constexpr double kR1 = 1, kR2 = 2, kR3 = 1, kC1 = 1, kC2 = 0.5;
  static constexpr double kTau = kC1 * (kR1 + kR2), kTauC = kR3 * kC2;
  int size() const override { return 3; }
  UnknownKind kind(int) const override { return D; }
  const Pattern& pattern() const override { return pattern_; }
  EvalStatus load(double, const Vector& x, const Predicates&, Load& out) override {
    const double u = x[0] - x[1];
    out.q[0] = kC1 * u;
    out.q[1] = -kC1 * u;
    out.q[2] = kC2 * x[2];
    out.f[0] = (x[0] - 1) / kR1;
    out.f[1] = x[1] / kR2;
    out.f[2] = (x[2] - 1) / kR3;
    if (!out.jacobian_requested) return EvalStatus::ok;
    auto at = [&](int row, int column) { return static_cast<std::size_t>(pattern_.index(row, column)); };
    out.dq_dx[at(0, 0)] = kC1;
    out.dq_dx[at(0, 1)] = -kC1;
    out.dq_dx[at(1, 0)] = -kC1;
    out.dq_dx[at(1, 1)] = kC1;
    out.dq_dx[at(2, 2)] = kC2;
    out.df_dx[at(0, 0)] = 1 / kR1;
    out.df_dx[at(1, 1)] = 1 / kR2;
    out.df_dx[at(2, 2)] = 1 / kR3;
    return EvalStatus::ok;
  }
  static Vector exact(double t) {
    const double v_b = kR2 / (kR1 + kR2) * std::exp(-t / kTau);
    return Vector{{1 - std::exp(-t / kTau) + v_b, v_b, 1 - std::exp(-t / kTauC)}};
  }

 private:
  static constexpr std::pair<int, int> kEntries[] = {{0, 0}, {0, 1}, {1, 0}, {1, 1}, {2, 2}};
  Pattern pattern_{3, kEntries};
};

// Dense output of v_c alone is its polynomial, with no solve at all. v_b's is too, on steps that
// vouch for it (a smooth exponential: each step's predictor, and the one before, within v_b's
// tolerance at the step's end, and the local error's response too); the first steps after the
// start do not, and their rows are checked by solves. Both are as accurate as the steps.
TEST(Integrator, DenseOutputOfAnUnknownSetByItsChargeIsThePolynomial) {
  struct Written {
    double worst = 0;  // against the closed form, in tolerances
    bool polynomial = true;  // every row equal to the polynomial
    long output_iterations = 0, steps = 0;
  };
  auto write = [](int unknown) {
    RcPair model;
    Options options;
    options.rtol = 1e-6;
    options.atol = 1e-9;
    Integrator integrator(model, options);
    Written written;
    EXPECT_TRUE(integrator.initialize(0.0, RcPair::exact(0))) << integrator.failure().reason;
    const std::vector<int> only{unknown};
    EXPECT_TRUE(run_until(integrator, 5.0, [&](const StepOutcome&) {
      for (double fraction : {0.25, 0.5, 0.75}) {
        const double t_at = integrator.time() - fraction * integrator.step_size();
        const double value = integrator.dense_output(t_at, only)[unknown], exact = RcPair::exact(t_at)[unknown];
        const double tolerance = options.rtol * std::abs(exact) + options.atol;
        written.worst = std::max(written.worst, std::abs(value - exact) / tolerance);
        written.polynomial = written.polynomial && value == integrator.interpolate(t_at)[unknown];
      }
    }));
    written.output_iterations = integrator.output_statistics().newton_iterations;
    written.steps = integrator.statistics().steps;
    return written;
  };
  const Written v_c = write(2), v_b = write(1);
  EXPECT_TRUE(v_c.polynomial);
  EXPECT_EQ(v_c.output_iterations, 0);
  EXPECT_GT(v_b.output_iterations, 0);
  EXPECT_LT(v_b.output_iterations, v_b.steps / 10);
  // Global errors: a few tolerances, as at the steps' ends.
  EXPECT_LT(v_c.worst, 10);
  EXPECT_LT(v_b.worst, 10);
}

TEST(Integrator, DenseOutputSolvesAnAlgebraicUnknownThatIsFlatInTheCharges) {
  BlockingJunction model;
  Options options;
  options.rtol = 1e-3;
  options.atol = 1e-6;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{BlockingJunction::kInitialCurrent, 0.5}}))
      << integrator.failure().reason;
  // Rows inside each step; the step blocks if the junction blocks at both of its ends.
  struct Row {
    double t, v;
    bool step_blocks;
  };
  std::vector<Row> written;
  auto blocks = [](double t, double v) { return std::abs(v - BlockingJunction::source(t)) < 1e-6; };
  bool blocked_before = false;
  ASSERT_TRUE(run_until(integrator, 20.0, [&](const StepOutcome&) {
    const bool blocked_after = blocks(integrator.time(), integrator.state()[1]);
    for (double fraction : {0.75, 0.5, 0.25}) {
      const double t_at = integrator.time() - fraction * integrator.step_size();
      written.push_back({t_at, integrator.dense_output(t_at)[1], blocked_before && blocked_after});
    }
    blocked_before = blocked_after;
  }));
  EXPECT_GT(std::count_if(written.begin(), written.end(), [](const Row& row) { return row.step_blocks; }),
            static_cast<long>(written.size() / 2));
  for (const Row& row : written) {
    // Within the tolerance (v itself is not error-tested, but rows are certified to it) of e
    // where the junction blocks; everywhere, between v's start and e's lowest value.
    if (row.step_blocks) {
      const double e = BlockingJunction::source(row.t);
      EXPECT_NEAR(row.v, e, options.rtol * std::abs(e) + options.atol) << "t = " << row.t;
    }
    EXPECT_GE(row.v, -1.5) << "t = " << row.t;
    EXPECT_LE(row.v, 0.5) << "t = " << row.t;
  }
}

// x' = -x beside an algebraic junction voltage 0 = exp(y / VT) - b(t), b = 1 + 1e6 sin(50 t)^2:
// y = VT ln b swings by 14 VT several times within a step that only x sets. Between the step's
// points the polynomial's y can be many VT below the solution, where Newton on the exponential
// overshoots by e^(distance / VT) and then creeps back one VT per iteration: dense output then
// continues from the step's start instead, where y is known.
class SwingingJunction : public SemiExplicitSystem {
 public:
  static constexpr double kThermal = 0.025;
  SwingingJunction() : SemiExplicitSystem({D, A}) {}
  static double drive(double t) { return 1 + 1e6 * std::pow(std::sin(50 * t), 2); }
  EvalStatus equations(double t, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = -z[0];
    out[1] = std::exp(z[1] / kThermal) - drive(t);
    return EvalStatus::ok;
  }
};

TEST(Integrator, DenseOutputSolvesWhereNewtonFromThePolynomialFails) {
  SwingingJunction model;
  Options options;
  options.rtol = 1e-6;
  options.atol = 1e-9;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{1.0, 0.0}})) << integrator.failure().reason;
  double worst = 0, worst_polynomial = 0;
  ASSERT_TRUE(run_until(integrator, 2.0, [&](const StepOutcome&) {
    for (int k = 1; k < 20; ++k) {
      const double t_at = integrator.time() - k / 20.0 * integrator.step_size();
      const double exact = SwingingJunction::kThermal * std::log(SwingingJunction::drive(t_at));
      worst = std::max(worst, std::abs(integrator.dense_output(t_at)[1] - exact));
      worst_polynomial = std::max(worst_polynomial, std::abs(integrator.interpolate(t_at)[1] - exact));
    }
  }));
  EXPECT_GT(worst_polynomial, 5 * SwingingJunction::kThermal);  // the case the test is about
  EXPECT_LT(worst, 1e-6);
}

// x' = -x beside 0 = y^3 + y - x - sin(10 t), a model that cannot be evaluated at t = blind
// (set after the steps): a row there has no solution. Its value is the polynomial's, and it is
// counted, so that the user is told; a row elsewhere in the same step is solved. The steps
// follow x; y's sine, which the error test does not see, keeps them from vouching for their
// polynomial.
class BlindInstant : public SemiExplicitSystem {
 public:
  BlindInstant() : SemiExplicitSystem({D, A}) {}
  double blind = -1;
  static double residual(double t, const Vector& z) { return z[1] * z[1] * z[1] + z[1] - z[0] - std::sin(10 * t); }
  EvalStatus equations(double t, const Vector& z, const Predicates&, Vector& out) override {
    if (t == blind) return EvalStatus::outside_domain;
    out[0] = -z[0];
    out[1] = residual(t, z);
    return EvalStatus::ok;
  }
};

TEST(Integrator, DenseOutputWithoutASolutionIsThePolynomialAndIsCounted) {
  BlindInstant model;
  Options options;
  options.rtol = 1e-6;
  options.atol = 1e-9;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{1.0, 0.6823278038280193}})) << integrator.failure().reason;
  while (integrator.time() < 0.5) ASSERT_NE(integrator.step(1.0).kind, StepKind::failed) << integrator.failure().reason;
  const double midpoint = integrator.time() - 0.5 * integrator.step_size();
  model.blind = midpoint;  // where the step's polynomial is checked, too: nothing certifies it
  EXPECT_EQ(integrator.dense_output(midpoint), integrator.interpolate(midpoint));
  EXPECT_EQ(integrator.output_statistics().unsolved_points, 1);
  const double quarter = integrator.time() - 0.25 * integrator.step_size();
  const Vector row = integrator.dense_output(quarter);
  EXPECT_LT(std::abs(BlindInstant::residual(quarter, row)), 1e-7);
  EXPECT_EQ(integrator.output_statistics().unsolved_points, 1);
  EXPECT_EQ(integrator.statistics().unsolved_points, 0);
}

// The first step from a consistent state is the trapezoidal rule (local error h^3 x''' / 12), not
// backward Euler (h^2 x'' / 2): on x' = -x a first step of 1e-3 leaves 8e-11, where backward
// Euler would leave 5e-7.
TEST(Integrator, FirstStepIsOfSecondOrder) {
  Decay decay(1.0);
  Options options;
  options.rtol = 1e-6;
  options.atol = 1e-9;
  options.initial_step = 1e-3;
  Integrator integrator(decay, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0))) << integrator.failure().reason;
  ASSERT_EQ(integrator.step(10.0).kind, StepKind::accepted);
  const double h = integrator.step_size();
  ASSERT_EQ(h, 1e-3);
  EXPECT_LT(std::abs(integrator.state()[0] - std::exp(-h)), h * h * h / 6);
}

// 0 = y^3 - 3 y + 1e-9 y - 3000 t: a branch of solutions from y(0) = 0 that ends at the fold
// y = -1, t = 2/3 ms; past it the only solution is on another branch (y > 2). No charge is
// error-tested, so only max_step sets the steps: whichever they are, the run must stop at the
// fold (its last points within the tolerance of it), not go on along the other branch.
class Fold : public SemiExplicitSystem {
 public:
  Fold() : SemiExplicitSystem({A}) {}
  EvalStatus equations(double t, const Vector& z, const Predicates&, Vector& out) override {
    const double y = z[0];
    out[0] = y * y * y - 3 * y + 1e-9 * y - 3000 * t;
    return EvalStatus::ok;
  }
  bool has_equation_jacobian() const override { return true; }
  bool equation_jacobian(double, const Vector& z, const Predicates&, std::vector<double>& values) override {
    values[0] = 3 * z[0] * z[0] - 3 + 1e-9;
    return true;
  }
};

TEST(Integrator, StopsWhereAnAlgebraicBranchEndsWhereverTheStepsFall) {
  const double fold = (2 + 1e-9) / 3000;  // y = -1
  for (int k = 0; k < 400; ++k) {
    Fold model;
    Options options;
    options.rtol = 1e-3;
    options.atol = 1e-6;
    options.time_scale = 1e-3;
    options.max_step = 2e-6 * (1 + k * 0.037);
    Integrator integrator(model, options);
    ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(1))) << integrator.failure().reason;
    EXPECT_FALSE(run_until(integrator, 1e-3)) << "max_step " << options.max_step << ": went on to y = " << integrator.state()[0];
    EXPECT_NEAR(integrator.time(), fold, 1e-3 * fold) << "max_step " << options.max_step;
    EXPECT_NEAR(integrator.state()[0], -1.0, 1e-2) << "max_step " << options.max_step;
  }
}

// Fold beside a charge that decays (x' = -1000 x, dense steps): the run stops at the fold,
// whichever limit stops it (Newton's failures or the step minimum), and names the fold's unknown,
// not the one the error test last weighed.
class FoldBesideDecay : public SemiExplicitSystem {
 public:
  FoldBesideDecay() : SemiExplicitSystem({D, A}, {{0, 0}, {1, 1}}) {}
  EvalStatus equations(double t, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = -1000 * z[0];
    const double y = z[1];
    out[1] = y * y * y - 3 * y + 1e-9 * y - 3000 * t;
    return EvalStatus::ok;
  }
};

TEST(Integrator, StopAtAFoldNamesTheFoldsUnknown) {
  const double fold = (2 + 1e-9) / 3000;
  for (double min_step : {0.0, 1e-12, 1e-10, 1e-9, 1e-8}) {
    FoldBesideDecay model;
    Options options;
    options.rtol = 1e-3;
    options.atol = 1e-6;
    options.time_scale = 1e-3;
    options.min_step = min_step;
    Integrator integrator(model, options);
    Vector start(2);
    start << 1, 0;
    ASSERT_TRUE(integrator.initialize(0.0, start)) << integrator.failure().reason;
    EXPECT_FALSE(run_until(integrator, 1e-3)) << "min_step " << min_step;
    EXPECT_NEAR(integrator.time(), fold, 1e-3 * fold) << "min_step " << min_step;
    EXPECT_EQ(integrator.failure().unknown, 1) << "min_step " << min_step << ": " << integrator.failure().reason;
  }
}

// A track-and-hold: x' = g(t) (t - x), the conductance g = G / (1 + e^((t - 1) / TAU)) falling
// from G = 1e6 to nothing within a few TAU = 1e-5 of t = 1, inside one step. Before, x tracks
// t within 2 / G (where g >= G / 2, e' = 1 - g e with e = t - x keeps e <= 2 / G); after, x
// moves by at most the integral of g e, below G (e(1) TAU + TAU^2) = 1.2e-4: it holds
// 1 - 2e-6 <= x <= 1 + 1.2e-4 from then on. Modified Newton on a matrix factored while tracking
// (G times stiffer than the one in the hold) finds any residual small: such a matrix must not
// confirm the step's convergence, or x goes on tracking t until the matrix is refreshed.
class TrackAndHold : public SemiExplicitSystem {
 public:
  TrackAndHold() : SemiExplicitSystem({D}) {}
  static constexpr double kG = 1e6, kTau = 1e-5;
  static double conductance(double t) { return kG / (1 + std::exp((t - 1) / kTau)); }
  EvalStatus equations(double t, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = conductance(t) * (t - z[0]);
    return EvalStatus::ok;
  }
  bool has_equation_jacobian() const override { return true; }
  bool equation_jacobian(double t, const Vector&, const Predicates&, std::vector<double>& values) override {
    values[0] = -conductance(t);
    return true;
  }
};

TEST(Integrator, HoldsWhereTheMatrixHeldWasFactoredWhileTracking) {
  for (int k = 0; k < 40; ++k) {
    TrackAndHold model;
    Options options;
    options.rtol = 1e-4;
    options.atol = 1e-6;
    options.max_step = 1e-2 * (1 + k * 0.13);
    Integrator integrator(model, options);
    ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(1))) << integrator.failure().reason;
    ASSERT_TRUE(run_until(integrator, 3.0)) << integrator.failure().reason;
    EXPECT_NEAR(integrator.state()[0], 1.0, 1e-3) << "max_step " << options.max_step;
  }
}

// An index-1 DAE: x' = -y, 0 = y - x^2 (x = 1 / (1 + t)); the algebraic y is not error-tested.
class IndexOne : public SemiExplicitSystem {
 public:
  IndexOne() : SemiExplicitSystem({D, A}) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = -z[1];
    out[1] = z[1] - z[0] * z[0];
    return EvalStatus::ok;
  }
};

TEST(Integrator, IndexOneDaeWithInconsistentInitialAlgebraicValue) {
  IndexOne dae;
  Options options;
  options.rtol = 1e-7;
  options.atol = 1e-9;
  Integrator integrator(dae, options);
  // y0 = 5 is inconsistent: initialization must bring it to x0^2 = 1.
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{1.0, 5.0}})) << integrator.failure().reason;
  // Consistent to the short derivative step that re-initialization takes (1e-8 of a step).
  EXPECT_NEAR(integrator.state()[1], 1.0, 1e-9);
  ASSERT_TRUE(run_until(integrator, 9.0));
  EXPECT_NEAR(integrator.state()[0], 0.1, 1e-6);
  EXPECT_NEAR(integrator.state()[1], 0.01, 1e-7);
}

// x' = s(t) with a source corner at t = 0.25 (slope 1 before, -2 after): the step must end
// exactly at the corner and restart there.
class Corner : public SemiExplicitSystem {
 public:
  Corner() : SemiExplicitSystem({D}) {}
  EvalStatus equations(double t, const Vector&, const Predicates&, Vector& out) override {
    out[0] = t < 0.25 ? t : 0.25 - 2 * (t - 0.25);
    return EvalStatus::ok;
  }
  double next_time_event(double t) const override {
    return t < 0.25 ? 0.25 : std::numeric_limits<double>::infinity();
  }
};

TEST(Integrator, TimeEventsAreHitExactly) {
  Corner corner;
  Options options;
  options.rtol = 1e-8;
  options.atol = 1e-12;
  Integrator integrator(corner, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(1))) << integrator.failure().reason;
  bool hit = false;
  ASSERT_TRUE(run_until(integrator, 1.0, [&](const StepOutcome& outcome) {
    if (outcome.kind == StepKind::time_event) {
      hit = true;
      EXPECT_EQ(outcome.t, 0.25);
      EXPECT_NEAR(integrator.state()[0], 0.25 * 0.25 / 2, 1e-9);
    }
  }));
  EXPECT_TRUE(hit);
  // x(1) = 1/32 + 0.25*0.75 - 0.75^2 = -0.34375.
  EXPECT_NEAR(integrator.state()[0], 0.03125 + 0.1875 - 0.5625, 1e-7);
  EXPECT_EQ(integrator.statistics().time_events, 1);
}

TEST(Integrator, DenseOutputCoversTheStepThatEndsAtACorner) {
  Corner corner;
  Options options;
  options.rtol = 1e-8;
  options.atol = 1e-12;
  Integrator integrator(corner, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Zero(1))) << integrator.failure().reason;
  for (;;) {
    const double t_before = integrator.time();
    const StepOutcome outcome = integrator.step(1.0);
    ASSERT_NE(outcome.kind, StepKind::failed) << integrator.failure().reason;
    if (outcome.kind != StepKind::time_event) continue;
    // The restart at the corner has begun a new history; the step that ended there still
    // interpolates x = t^2 / 2.
    ASSERT_LT(t_before, 0.25);
    for (double fraction : {0.2, 0.5, 0.8}) {
      const double t_at = t_before + fraction * (0.25 - t_before);
      EXPECT_NEAR(integrator.dense_output(t_at)[0], t_at * t_at / 2, 1e-9) << "t = " << t_at;
    }
    break;
  }
}

// x' = -x, x(0) = 1, with a model that is undefined for x < 0 (like a logarithm of a state
// that is positive on the physical path). A first step that is far too long predicts x < 0:
// that step is cut, not fatal.
class PositiveDecay : public SemiExplicitSystem {
 public:
  PositiveDecay() : SemiExplicitSystem({D}) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    if (z[0] < 0) return EvalStatus::outside_domain;
    out[0] = -z[0];
    return EvalStatus::ok;
  }
};

TEST(Integrator, ModelOutsideItsDomainCutsTheStepAndTheRunSucceeds) {
  PositiveDecay model;
  Options options;
  options.rtol = 1e-6;
  options.atol = 1e-10;
  options.initial_step = 3;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0))) << integrator.failure().reason;
  ASSERT_TRUE(run_until(integrator, 10.0)) << integrator.failure().reason;
  EXPECT_NEAR(integrator.state()[0], std::exp(-10.0), 1e-4 * std::exp(-10.0));
  EXPECT_GT(integrator.statistics().rejected_domain, 0);
}

// Whether the arithmetic in effect reads the smallest subnormal as zero (volatile: computed at
// run time, in the floating-point mode of the moment).
bool subnormals_read_as_zero() {
  volatile double subnormal = std::numeric_limits<double>::denorm_min();
  volatile double one = 1.0;
  return subnormal * one == 0.0;
}

// x' = -x, noting whether every evaluation ran with subnormals flushed.
class DecayWatchingSubnormals : public SemiExplicitSystem {
 public:
  DecayWatchingSubnormals() : SemiExplicitSystem({D}) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    ++evaluations;
    if (!subnormals_read_as_zero()) ++evaluations_with_subnormals;
    out[0] = -z[0];
    return EvalStatus::ok;
  }
  int evaluations = 0;
  int evaluations_with_subnormals = 0;
};

TEST(Integrator, SolvesWithSubnormalsFlushedAndLeavesTheCallersModeAlone) {
  if (!SubnormalsFlushed::supported) GTEST_SKIP() << "no flush-to-zero mode on this processor";
  ASSERT_FALSE(subnormals_read_as_zero());
  DecayWatchingSubnormals decay;
  Options options;
  SteadyState bias = steady_state(decay, 0.0, Vector::Constant(1, 1.0), {}, options);
  ASSERT_TRUE(bias.converged) << bias.message;
  EXPECT_FALSE(subnormals_read_as_zero());
  Integrator integrator(decay, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector::Constant(1, 1.0))) << integrator.failure().reason;
  ASSERT_TRUE(run_until(integrator, 1.0, [](const StepOutcome&) { EXPECT_FALSE(subnormals_read_as_zero()); }));
  integrator.dense_output(0.5);
  EXPECT_FALSE(subnormals_read_as_zero());
  EXPECT_GT(decay.evaluations, 0);
  EXPECT_EQ(decay.evaluations_with_subnormals, 0);
}

// The finite-difference Jacobian (pattern-coloured) agrees with the analytic one.
class Nonlinear : public System {
 public:
  Nonlinear() {
    std::vector<std::pair<int, int>> entries{{0, 1}, {1, 0}, {1, 2}, {2, 0}, {3, 2}, {2, 3}};
    pattern_ = Pattern(4, entries);
  }
  int size() const override { return 4; }
  UnknownKind kind(int) const override { return D; }
  const Pattern& pattern() const override { return pattern_; }
  bool analytic_jacobian() const override { return analytic; }
  EvalStatus load(double t, const Vector& x, const Predicates&, Load& out) override {
    out.f[0] = std::sin(x[1]) + x[0] * t;
    out.f[1] = x[0] * x[2] + std::exp(x[1]);
    out.f[2] = x[3] * x[3] - x[0];
    out.f[3] = std::cos(x[2]) + x[3];
    out.q[0] = x[0] * x[0] * x[0];
    out.q[1] = x[1] + 0.5 * x[0];
    out.q[2] = std::tanh(x[2]);
    out.q[3] = x[3] * x[2];
    if (!out.jacobian_requested) return EvalStatus::ok;
    auto at = [&](int r, int c) -> std::size_t { return static_cast<std::size_t>(pattern_.index(r, c)); };
    out.df_dx[at(0, 0)] = t;
    out.df_dx[at(0, 1)] = std::cos(x[1]);
    out.df_dx[at(1, 0)] = x[2];
    out.df_dx[at(1, 1)] = std::exp(x[1]);
    out.df_dx[at(1, 2)] = x[0];
    out.df_dx[at(2, 3)] = 2 * x[3];
    out.df_dx[at(2, 0)] = -1;
    out.df_dx[at(3, 2)] = -std::sin(x[2]);
    out.df_dx[at(3, 3)] = 1;
    out.dq_dx[at(0, 0)] = 3 * x[0] * x[0];
    out.dq_dx[at(1, 1)] = 1;
    out.dq_dx[at(1, 0)] = 0.5;
    out.dq_dx[at(2, 2)] = 1 - std::pow(std::tanh(x[2]), 2);
    out.dq_dx[at(3, 3)] = x[2];
    out.dq_dx[at(3, 2)] = x[3];
    return EvalStatus::ok;
  }
  bool analytic = true;

 private:
  Pattern pattern_;
};

TEST(NewtonMatrix, FiniteDifferencesAgreeWithTheAnalyticJacobian) {
  Nonlinear model;
  Statistics statistics;
  Vector typical = Vector::Constant(4, 1e-6);
  const Vector x{{0.7, -0.3, 1.1, 0.4}};
  const double cj = 3.0;
  std::vector<double> analytic_f, analytic_q;
  {
    NewtonMatrix analytic(model, statistics, typical);
    ASSERT_EQ(analytic.factor(0.5, x, {}, cj), NewtonMatrix::Outcome::ok);
    analytic_f = analytic.load().df_dx;
    analytic_q = analytic.load().dq_dx;
  }
  model.analytic = false;
  NewtonMatrix numeric(model, statistics, typical);
  ASSERT_EQ(numeric.factor(0.5, x, {}, cj), NewtonMatrix::Outcome::ok);
  for (std::size_t k = 0; k < analytic_f.size(); ++k) {
    EXPECT_NEAR(numeric.load().df_dx[k], analytic_f[k], 1e-6 * (1 + std::abs(analytic_f[k])));
    EXPECT_NEAR(numeric.load().dq_dx[k], analytic_q[k], 1e-6 * (1 + std::abs(analytic_q[k])));
  }
}

// Nonlinear's charges: q0 = x0^3 and q2 = tanh(x2) each depend on one unknown; q1 and q3 on two.
TEST(NewtonMatrix, FindsTheUnknownsThatAreFunctionsOfOneCharge) {
  Nonlinear model;
  Statistics statistics;
  NewtonMatrix newton(model, statistics, Vector::Constant(4, 1e-6));
  std::vector<char> determined;
  ASSERT_EQ(newton.charge_determined(0.5, Vector{{0.7, -0.3, 1.1, 0.4}}, {}, determined), EvalStatus::ok);
  EXPECT_EQ(determined, (std::vector<char>{1, 0, 1, 0}));
}

// A resistor from 1 V into a diode: (x - 1) / R + Is (exp(x / Vt) - 1) = 0.
class DiodeBias : public SemiExplicitSystem {
 public:
  DiodeBias() : SemiExplicitSystem({A}) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = current(z[0]);
    return EvalStatus::ok;
  }
  static double current(double v) { return (v - 1.0) / 1e3 + 1e-14 * (std::exp(v / 0.025) - 1); }
};

TEST(SteadyState, SolvesANonlinearBiasPoint) {
  DiodeBias bias;
  Options options;
  options.rtol = 1e-9;
  options.atol = 1e-12;
  SteadyState result = steady_state(bias, 0.0, Vector::Zero(1), {}, options);
  ASSERT_TRUE(result.converged) << result.message;
  // Reference by bisection (the current is increasing in v).
  double low = 0, high = 1;
  for (int i = 0; i < 200; ++i) {
    double middle = 0.5 * (low + high);
    (DiodeBias::current(middle) > 0 ? high : low) = middle;
  }
  EXPECT_NEAR(result.x[0], 0.5 * (low + high), 1e-9);
}

}  // namespace
}  // namespace padae
