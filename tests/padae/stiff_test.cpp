// Stiff problems with published references (the Bari test set for IVP solvers).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "padae/integrator.hpp"
#include "padae/semi_explicit.hpp"
#include "run_until.hpp"
#include "transistor_amplifier.hpp"

namespace padae {
namespace {

using testing::run_until;
using testing::TransistorAmplifier;
constexpr auto D = UnknownKind::differential;
constexpr auto A = UnknownKind::algebraic;

double relative_error(double value, double reference) {
  return std::abs(value - reference) / std::abs(reference);
}

// Robertson's chemical kinetics as an index-1 DAE (y3 from mass conservation), to t = 1e11.
class Robertson : public SemiExplicitSystem {
 public:
  Robertson() : SemiExplicitSystem({D, D, A}) {}
  EvalStatus equations(double, const Vector& y, const Predicates&, Vector& out) override {
    out[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
    out[1] = 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] * y[1];
    out[2] = y[0] + y[1] + y[2] - 1;
    return EvalStatus::ok;
  }
  bool has_equation_jacobian() const override { return true; }
  bool equation_jacobian(double, const Vector& y, const Predicates&, std::vector<double>& j) override {
    auto at = [&](int r, int c) { return static_cast<std::size_t>(pattern().index(r, c)); };
    j[at(0, 0)] = -0.04;
    j[at(0, 1)] = 1e4 * y[2];
    j[at(0, 2)] = 1e4 * y[1];
    j[at(1, 0)] = 0.04;
    j[at(1, 1)] = -1e4 * y[2] - 6e7 * y[1];
    j[at(1, 2)] = -1e4 * y[1];
    j[at(2, 0)] = j[at(2, 1)] = j[at(2, 2)] = 1;
    return true;
  }
  double absolute_tolerance(int unknown, double) const override {
    static const double scale[3] = {1e-14, 1e-20, 1e-10};
    return scale[unknown];
  }
};

TEST(Stiff, RobertsonDaeToOneHundredBillionSeconds) {
  Robertson model;
  Options options;
  options.rtol = 1e-8;
  options.time_scale = 1e11;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{1.0, 0.0, 0.0}})) << integrator.failure().reason;
  ASSERT_TRUE(run_until(integrator, 1e11)) << integrator.failure().reason;
  const Vector& y = integrator.state();
  EXPECT_LT(relative_error(y[0], 0.2083340149701255e-07), 1e-4);
  EXPECT_LT(relative_error(y[1], 0.8333360770334713e-13), 1e-4);
  EXPECT_LT(relative_error(y[2], 0.9999999791665050), 1e-10);
  RecordProperty("steps", static_cast<int>(integrator.statistics().steps));
}

// Van der Pol with epsilon = 1e-6 (mu = 1e6 in the scaled form), y(0) = (2, 0), to t = 2.
class VanDerPol : public SemiExplicitSystem {
 public:
  VanDerPol() : SemiExplicitSystem({D, D}) {}
  EvalStatus equations(double, const Vector& y, const Predicates&, Vector& out) override {
    out[0] = y[1];
    out[1] = ((1 - y[0] * y[0]) * y[1] - y[0]) / 1e-6;
    return EvalStatus::ok;
  }
  bool has_equation_jacobian() const override { return true; }
  bool equation_jacobian(double, const Vector& y, const Predicates&, std::vector<double>& j) override {
    auto at = [&](int r, int c) { return static_cast<std::size_t>(pattern().index(r, c)); };
    j[at(0, 1)] = 1;
    j[at(1, 0)] = (-2 * y[0] * y[1] - 1) / 1e-6;
    j[at(1, 1)] = (1 - y[0] * y[0]) / 1e-6;
    return true;
  }
};

TEST(Stiff, VanDerPolWithMuOneMillion) {
  for (double rtol : {1e-6, 1e-8}) {
    VanDerPol model;
    Options options;
    options.rtol = rtol;
    options.atol = rtol;
    options.time_scale = 2;
    Integrator integrator(model, options);
    ASSERT_TRUE(integrator.initialize(0.0, Vector{{2.0, 0.0}})) << integrator.failure().reason;
    ASSERT_TRUE(run_until(integrator, 2.0)) << integrator.failure().reason;
    // Global error is a modest multiple of the local tolerance on this problem.
    EXPECT_LT(relative_error(integrator.state()[0], 0.1706167732170483e1), 300 * rtol) << rtol;
    EXPECT_LT(relative_error(integrator.state()[1], -0.8928097010247975), 300 * rtol) << rtol;
  }
}

TEST(Stiff, TransistorAmplifierReachesDigitsConsistentWithTheTolerance) {
  const Vector y0 = TransistorAmplifier::initial_state();
  for (double rtol : {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10}) {
    TransistorAmplifier model;
    Options options;
    options.rtol = rtol;
    options.atol = rtol;
    options.time_scale = 0.2;
    Integrator integrator(model, options);
    ASSERT_TRUE(integrator.initialize(0.0, y0)) << integrator.failure().reason;
    ASSERT_TRUE(run_until(integrator, 0.2)) << integrator.failure().reason;
    double digits = TransistorAmplifier::correct_digits(integrator.state());
    // The local tolerance bounds each step's error in the charges; the second and third stages
    // amplify errors through the transistors' exponentials (an error of 4e-9 V in the base-
    // emitter voltage moves the collector current by 1.5e-7 relative), so the global error is
    // the tolerance times that amplification: up to about 300 here.
    EXPECT_GT(digits, -std::log10(rtol) - 2.5) << "rtol " << rtol << " steps " << integrator.statistics().steps;
  }
}

// A boost converter's inductor discharging through a diode into a fixed output, its switch node
// held otherwise by a leakage alone (g): i' = (Vin - v) / L, 0 = i - g v - Is (exp((v - Vout) /
// n VT) - 1). The current ramps down to zero and stays there; the node then sits at Vin, held by
// a mode of time constant L g' (picoseconds, g' the node's conductance) that ties it to L di/dt.
// Every solution has i' <= 0, so v >= Vin throughout.
class DiodeTurnOff : public SemiExplicitSystem {
 public:
  static constexpr double inductance = 22e-6, input = 5, output = 15, leakage = 1e-7;
  static constexpr double saturation_current = 1e-9, emission_voltage = 1.5 * 0.025852;
  DiodeTurnOff() : SemiExplicitSystem({D, A}) {}
  EvalStatus equations(double, const Vector& y, const Predicates&, Vector& out) override {
    out[0] = (input - y[1]) / inductance;
    out[1] = y[0] - leakage * y[1] - saturation_current * std::expm1((y[1] - output) / emission_voltage);
    return EvalStatus::ok;
  }
  bool has_equation_jacobian() const override { return true; }
  bool equation_jacobian(double, const Vector& y, const Predicates&, std::vector<double>& j) override {
    auto at = [&](int r, int c) { return static_cast<std::size_t>(pattern().index(r, c)); };
    j[at(0, 1)] = -1 / inductance;
    j[at(1, 0)] = 1;
    j[at(1, 1)] = -leakage - saturation_current / emission_voltage * std::exp((y[1] - output) / emission_voltage);
    return true;
  }
  // The junction's voltage: its current turns off where it crosses zero.
  int kink_count() const override { return 1; }
  void kinks(const Vector& y, Vector& out) const override { out[0] = y[1] - output; }
};

TEST(Stiff, NodeTiedToAnInductorsDerivativeStaysAtItsInputAfterTheDiodeTurnsOff) {
  // Without the retake at order 1, BDF2's derivative across the turn-off (the history's ramp,
  // then flat) swung v below Vin on the steps after it: down to 2.0 V at rtol 1e-3, 2.6 V at 1e-4
  // and 4.1 V at 1e-5.
  for (double rtol : {1e-3, 1e-4, 1e-5})
    for (double start_current : {1.0, 0.7, 0.45, 0.3, 0.2}) {
      DiodeTurnOff model;
      Options options;
      options.rtol = rtol;
      options.time_scale = 4e-6;
      Integrator integrator(model, options);
      const double conducting = DiodeTurnOff::output + DiodeTurnOff::emission_voltage *
                                                           std::log1p(start_current / DiodeTurnOff::saturation_current);
      ASSERT_TRUE(integrator.initialize(0.0, Vector{{start_current, conducting}}))
          << integrator.failure().reason;
      double lowest = std::numeric_limits<double>::infinity();
      auto track = [&](const StepOutcome&) { lowest = std::min(lowest, integrator.state()[1]); };
      ASSERT_TRUE(run_until(integrator, 4e-6, track)) << integrator.failure().reason;
      EXPECT_GT(lowest, DiodeTurnOff::input * (1 - 10 * rtol)) << "rtol " << rtol << ", i(0) " << start_current;
      // Turned off: the leakage's current at Vin, less the blocked junction's IS.
      const double resting = DiodeTurnOff::leakage * DiodeTurnOff::input - DiodeTurnOff::saturation_current;
      EXPECT_NEAR(integrator.state()[0], resting, 1e-3 * resting);
      EXPECT_NEAR(integrator.state()[1], DiodeTurnOff::input, 10 * rtol * DiodeTurnOff::input);
    }
}

}  // namespace
}  // namespace padae
