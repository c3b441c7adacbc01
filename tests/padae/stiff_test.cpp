// Stiff problems with published references (the Bari test set for IVP solvers).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "padae/integrator.hpp"
#include "padae/semi_explicit.hpp"
#include "run_until.hpp"

namespace padae {
namespace {

using testing::run_until;
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

// The Bari test set's transistor amplifier: M y' = f(t, y), index 1, eight node voltages.
// In charge form q = M y holds the five capacitor charges.
class TransistorAmplifier : public System {
 public:
  TransistorAmplifier() {
    std::vector<std::pair<int, int>> entries;
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 8; ++j) entries.emplace_back(i, j);
    pattern_ = Pattern(8, entries);
  }
  int size() const override { return 8; }
  UnknownKind kind(int) const override { return D; }
  const Pattern& pattern() const override { return pattern_; }
  EvalStatus load(double t, const Vector& y, const Predicates&, Load& out) override {
    const double ub = 6, uf = 0.026, alpha = 0.99, beta = 1e-6, r0 = 1000, r = 9000;
    const double c[5] = {1e-6, 2e-6, 3e-6, 4e-6, 5e-6};
    const double input = 0.1 * std::sin(200 * std::numbers::pi * t);
    const double e1 = std::exp((y[1] - y[2]) / uf), e2 = std::exp((y[4] - y[5]) / uf);
    const double fac1 = beta * (e1 - 1), fac2 = beta * (e2 - 1);
    // The test set writes M y' - f(t, y) = 0; so here f_charge = -f.
    double f[8] = {(y[0] - input) / r0,
                   y[1] / r + (y[1] - ub) / r + (1 - alpha) * fac1,
                   y[2] / r - fac1,
                   (y[3] - ub) / r + alpha * fac1,
                   y[4] / r + (y[4] - ub) / r + (1 - alpha) * fac2,
                   y[5] / r - fac2,
                   (y[6] - ub) / r + alpha * fac2,
                   y[7] / r};
    for (int i = 0; i < 8; ++i) out.f[i] = -f[i];
    out.q[0] = -c[0] * y[0] + c[0] * y[1];
    out.q[1] = -out.q[0];
    out.q[2] = -c[1] * y[2];
    out.q[3] = -c[2] * y[3] + c[2] * y[4];
    out.q[4] = -out.q[3];
    out.q[5] = -c[3] * y[5];
    out.q[6] = -c[4] * y[6] + c[4] * y[7];
    out.q[7] = -out.q[6];
    if (!out.jacobian_requested) return EvalStatus::ok;
    auto df = [&](int row, int column, double value) { out.df_dx[static_cast<std::size_t>(pattern_.index(row, column))] -= value; };
    auto dq = [&](int row, int column, double value) { out.dq_dx[static_cast<std::size_t>(pattern_.index(row, column))] += value; };
    const double d1 = beta * e1 / uf, d2 = beta * e2 / uf;
    df(0, 0, 1 / r0);
    df(1, 1, 2 / r + (1 - alpha) * d1);
    df(1, 2, -(1 - alpha) * d1);
    df(2, 2, 1 / r + d1);
    df(2, 1, -d1);
    df(3, 3, 1 / r);
    df(3, 1, alpha * d1);
    df(3, 2, -alpha * d1);
    df(4, 4, 2 / r + (1 - alpha) * d2);
    df(4, 5, -(1 - alpha) * d2);
    df(5, 5, 1 / r + d2);
    df(5, 4, -d2);
    df(6, 6, 1 / r);
    df(6, 4, alpha * d2);
    df(6, 5, -alpha * d2);
    df(7, 7, 1 / r);
    const int first[3] = {0, 3, 6};
    const double pair_c[3] = {c[0], c[2], c[4]};
    for (int k = 0; k < 3; ++k) {
      int a = first[k], b = first[k] + 1;
      dq(a, a, -pair_c[k]);
      dq(a, b, pair_c[k]);
      dq(b, a, pair_c[k]);
      dq(b, b, -pair_c[k]);
    }
    dq(2, 2, -c[1]);
    dq(5, 5, -c[3]);
    return EvalStatus::ok;
  }

 private:
  Pattern pattern_;
};

TEST(Stiff, TransistorAmplifierReachesDigitsConsistentWithTheTolerance) {
  const double reference[8] = {-0.5562145012262709e-02, 0.3006522471903042e+01,
                               0.2849958788608128e+01, 0.2926422536206241e+01,
                               0.2704617865010554e+01, 0.2761837778393145e+01,
                               0.4770927631616772e+01, 0.1236995868091548e+01};
  const double ub = 6;
  const Vector y0{{0, ub / 2, ub / 2, ub, ub / 2, ub / 2, ub, 0}};
  for (double rtol : {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10}) {
    TransistorAmplifier model;
    Options options;
    options.rtol = rtol;
    options.atol = rtol;
    options.time_scale = 0.2;
    Integrator integrator(model, options);
    ASSERT_TRUE(integrator.initialize(0.0, y0)) << integrator.failure().reason;
    ASSERT_TRUE(run_until(integrator, 0.2)) << integrator.failure().reason;
    double worst = 0;
    for (int i = 0; i < 8; ++i)
      worst = std::max(worst, std::abs(integrator.state()[i] - reference[i]) / (std::abs(reference[i]) + 1));
    double digits = -std::log10(worst);
    // The local tolerance bounds each step's error in the charges; the second and third stages
    // amplify errors through the transistors' exponentials (an error of 4e-9 V in the base-
    // emitter voltage moves the collector current by 1.5e-7 relative), so the global error is
    // the tolerance times that amplification: up to about 300 here.
    EXPECT_GT(digits, -std::log10(rtol) - 2.5) << "rtol " << rtol << " steps " << integrator.statistics().steps;
    if (rtol <= 1e-9) EXPECT_GT(digits, 8.0);
  }
}

}  // namespace
}  // namespace padae
