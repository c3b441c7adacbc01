#include "padae/damped_newton.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "padae/semi_explicit.hpp"

namespace padae {
namespace {

using Function = double (*)(double);

// One algebraic equation 0 = g(y) with its derivative, solved as a corrector equation (no
// charges: c plays no role).
// With a limit, the model accepts only that fraction of a step from y to y_next.
using Limit = double (*)(double y, double y_next);

class Scalar : public SemiExplicitSystem {
 public:
  Scalar(Function g, Function g_derivative, Limit limit = nullptr)
      : SemiExplicitSystem({UnknownKind::algebraic}), g_(g), g_derivative_(g_derivative), limit_(limit) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    ++evaluations;
    out[0] = g_(z[0]);
    return std::isfinite(out[0]) ? EvalStatus::ok : EvalStatus::outside_domain;
  }
  bool has_equation_jacobian() const override { return true; }
  bool equation_jacobian(double, const Vector& z, const Predicates&, std::vector<double>& values) override {
    values[0] = g_derivative_(z[0]);
    return true;
  }

  double newton_step_fraction(const Vector& z, const Vector& z_next) const override {
    return limit_ ? limit_(z[0], z_next[0]) : 1.0;
  }
  int evaluations = 0;

 private:
  Function g_, g_derivative_;
  Limit limit_;
};

struct Solve {
  NewtonOutcome outcome;
  double y;
  int evaluations;  // of g
};

// tolerance: of the correction, in volts.
Solve solve(Function g, Function g_derivative, double y_start, double tolerance = 1e-9, Limit limit = nullptr) {
  Scalar system(g, g_derivative, limit);
  Statistics statistics;
  NewtonMatrix newton(system, statistics, Vector::Constant(1, 1e-9));
  const Vector zero = Vector::Zero(1), held = Vector::Constant(1, y_start);
  const Predicates p;
  const CorrectorEquation equation{0.0, 1.0, zero, zero, held, p};
  Vector y = held;
  const Vector inverse_weight = Vector::Constant(1, 1 / tolerance);
  const NewtonOutcome outcome = solve_damped(newton, statistics, equation, inverse_weight, 0.33, 1e-3, 30, y);
  return {outcome, y[0], system.evaluations};
}

constexpr double kThermal = 0.025;

// A junction 0 = exp(y / VT) - 1e6 from 0.85 V below its solution: undamped Newton's first
// step lands near 1e6 e^20 VT, where the exponential overflows.
double junction(double y) { return std::exp(y / kThermal) - 1e6; }
double junction_derivative(double y) { return std::exp(y / kThermal) / kThermal; }

TEST(DampedNewton, ReachesAJunctionFromFarBelowItsSolution) {
  const Solve result = solve(junction, junction_derivative, -0.5);
  ASSERT_EQ(result.outcome, NewtonOutcome::converged) << result.y;
  EXPECT_NEAR(result.y, kThermal * std::log(1e6), 1e-9);
}

// The same junction with SPICE's limit (pnjlim from reverse bias: a step past 0.3 V stops at
// VT ln(y_next / VT)): the damping starts there instead of halving down from a whole step
// (some 44 halvings to the first trial accepted). 30 evaluations of g against 67.
TEST(DampedNewton, StartsTheDampingWhereTheModelLimitsTheStep) {
  const Limit pnjlim = [](double y, double y_next) {
    if (!(y <= 0 && y_next > 0.3)) return 1.0;
    return (kThermal * std::log(y_next / kThermal) - y) / (y_next - y);
  };
  const Solve limited = solve(junction, junction_derivative, -0.5, 1e-9, pnjlim);
  ASSERT_EQ(limited.outcome, NewtonOutcome::converged) << limited.y;
  EXPECT_NEAR(limited.y, kThermal * std::log(1e6), 1e-9);
  const Solve halving = solve(junction, junction_derivative, -0.5);
  EXPECT_LE(limited.evaluations, 32);
  EXPECT_GE(halving.evaluations, 60);
}

// A junction behind a 20 mOhm resistor from -1 V: 0 = (y + 1) / 0.02 + 1e-12 (exp(y / VT) - 1),
// solved from y = 1 V, where the junction conducts hard; the solution is y = -1 V within 1e-13.
// Each full Newton step from there lowers y by about VT, and the residual after it, on the matrix
// of the step's start, gives a correction of VT / e: at a loose tolerance of 40 mV that looks
// converged at 1 V. Only a correction on the matrix at the iterate itself can tell.
TEST(DampedNewton, TakesNoCorrectionOnAStaleMatrixForConvergence) {
  const Solve result = solve([](double y) { return (y + 1) / 0.02 + 1e-12 * std::expm1(y / kThermal); },
                             [](double y) { return 1 / 0.02 + 1e-12 * std::exp(y / kThermal) / kThermal; }, 1.0,
                             0.04);
  ASSERT_EQ(result.outcome, NewtonOutcome::converged) << result.y;
  EXPECT_NEAR(result.y, -1.0, 0.04);
}

// 0 = y^3 - 3 y - I on the middle branch (-1 < y < 1), whose end is the fold y = -1, I = 2.
// Before the fold Newton from near it finds the branch's root. Past it the only root is on the
// far branch (y > 2), where undamped Newton from near the fold lands from many starts (for
// I = 2.1, from y = -0.99 in 11 iterations); it must fail from every start instead.
double cubic_derivative(double y) { return 3 * y * y - 3; }
double current;  // I, for the captureless functions
double cubic(double y) { return y * y * y - 3 * y - current; }

TEST(DampedNewton, FindsTheRootOnItsBranchAndFailsPastTheBranchsFold) {
  current = 1.9;
  const Solve before = solve(cubic, cubic_derivative, -0.9);
  ASSERT_EQ(before.outcome, NewtonOutcome::converged);
  double low = -1, high = 0;  // the middle branch's root, by bisection (g decreases there)
  for (int i = 0; i < 100; ++i) {
    const double mid = (low + high) / 2;
    (cubic(mid) > 0 ? low : high) = mid;
  }
  EXPECT_NEAR(before.y, low, 1e-9);

  for (double past_fold : {2.02, 2.06, 2.1, 2.2}) {
    current = past_fold;
    for (int i = 0; i < 100; ++i) {
      const double start = -0.999 + 1e-3 * i;
      const Solve past = solve(cubic, cubic_derivative, start);
      EXPECT_NE(past.outcome, NewtonOutcome::converged) << "I = " << past_fold << ", from y = " << start
                                                        << ": landed at y = " << past.y;
    }
  }
}

}  // namespace
}  // namespace padae
