// Every device's analytic Jacobians against central differences of its own f and q.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "helpers.hpp"

namespace mna::test {
namespace {

using netlist::BinaryOperator;

void expect_jacobians_match_differences(Model& model, const Vector& x, const padae::Predicates& p) {
  const auto exact = evaluate(model, 0.3e-3, x, p);
  for (int column = 0; column < model.size(); ++column) {
    if (model.kind(column) == padae::UnknownKind::auxiliary) continue;
    const double h = 1e-6 * std::max(1.0, std::abs(x[column]));
    Vector up = x, down = x;
    up[column] += h, down[column] -= h;
    const auto plus = evaluate(model, 0.3e-3, up, p), minus = evaluate(model, 0.3e-3, down, p);
    for (int row = 0; row < model.size(); ++row) {
      const double df = (plus.f[row] - minus.f[row]) / (2 * h), dq = (plus.q[row] - minus.q[row]) / (2 * h);
      // Truncation error of the difference, plus the round-off of the rows' values over 2h.
      const double eps = std::numeric_limits<double>::epsilon();
      const double f_roundoff = 8 * eps * (std::abs(plus.f[row]) + std::abs(minus.f[row])) / (2 * h);
      const double q_roundoff = 8 * eps * (std::abs(plus.q[row]) + std::abs(minus.q[row])) / (2 * h);
      EXPECT_NEAR(exact.df(row, column), df, 1e-6 * std::abs(df) + f_roundoff + 1e-12)
          << "df/dx " << model.unknowns().label(row) << " / " << model.unknowns().label(column);
      EXPECT_NEAR(exact.dq(row, column), dq, 1e-6 * std::abs(dq) + q_roundoff + 1e-24)
          << "dq/dx " << model.unknowns().label(row) << " / " << model.unknowns().label(column);
    }
  }
}

// The devices whose derivatives depend on the predicates alone (Device::constant_jacobian).
CircuitSpec linear_devices() {
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 1.0).waveform = {Waveform::Shape::sine, {0, 1, 1e3}};
  c.add("r1", {"in", "a"}, 10.0);
  c.add("c1", {"a", "b"}, 1e-6);
  c.add("l1", {"b", "0"}, 1e-3);
  c.add("l2", {"c", "0"}, 2e-3);
  c.add("k1", {}, 0.9).controls = {"l1", "l2"};
  c.add("i1", {"c", "0"}, 1e-3);
  c.add("e1", {"d", "0", "a", "b"}, 2.0);
  c.add("g1", {"d", "0", "a", "0"}, 1e-3);
  c.add("f1", {"c", "0"}, 0.5).controls = {"v1"};
  c.add("h1", {"e", "0"}, 3.0).controls = {"l1"};
  c.add("d2", {"a", "d"}).model = {{"ideal", 1}, {"ron", 0.5}, {"roff", 1e5}, {"vfwd", 0.3}};
  c.add("d3", {"d", "e"}).model = {{"ideal", 1}};
  c.add("s1", {"a", "e", "b", "0"}).model = {{"vt", 0.5}, {"vh", 0.1}};
  c.add("s2", {"b", "d", "a", "0"}).model = {{"ron", 0.0}};
  c.add("w1", {"c", "e"}).controls = {"v1"};
  // A comparator choosing between affine expressions, one with a time-varying term.
  auto& b3 = c.add("b3", {"g", "0"});
  b3.expression = conditional(binary(BinaryOperator::greater, voltage("a"), voltage("d")),
                              binary(BinaryOperator::add, binary(BinaryOperator::multiply, number(2), voltage("b")),
                                     call("sin", {time()})),
                              binary(BinaryOperator::divide, current("l1"), number(4)));
  c.add("r3", {"g", "0"}, 1.0);
  return c;
}

CircuitSpec every_device() {
  CircuitSpec c = linear_devices();
  auto& d = c.add("d1", {"e", "a"});
  d.model = {{"is", 1e-12}, {"n", 1.2}, {"rs", 2.0}, {"cjo", 1e-12}, {"tt", 1e-9}, {"bv", 5.0}};
  // B sources: a smooth nonlinear current and a voltage with conditions and kinks.
  auto& b1 = c.add("b1", {"e", "0"});
  b1.expression_is_current = true;
  b1.expression = binary(BinaryOperator::multiply, call("tanh", {voltage("a", "b")}),
                         binary(BinaryOperator::power, call("exp", {binary(BinaryOperator::multiply, number(0.1), voltage("c"))}),
                                number(1.5)));
  auto& b2 = c.add("b2", {"f", "0"});
  b2.expression = conditional(binary(BinaryOperator::greater, voltage("a"), voltage("d")),
                              binary(BinaryOperator::multiply, current("l1"), call("abs", {voltage("e")})),
                              call("limit", {binary(BinaryOperator::divide, voltage("c"), voltage("b")), number(-1), number(2)}));
  c.add("r2", {"f", "0"}, 1.0);
  // MOSFETs with every part: body effect, series resistances, junction and overlap charges.
  auto& m1 = c.add("m1", {"a", "b", "c", "0"}, 1);
  m1.model = {{"vto", 0.2}, {"kp", 1e-3}, {"gamma", 0.4}, {"lambda", 0.05}, {"rd", 3.0}, {"rs", 2.0},
              {"cbd", 1e-12}, {"cj", 1e-4}, {"cjsw", 1e-10}, {"cgso", 1e-9}, {"cgdo", 1e-9}, {"cgbo", 1e-9}};
  m1.instance_parameters = {{"w", 10e-6}, {"l", 1e-6}, {"as", 1e-11}, {"ps", 1e-5}, {"pd", 1e-5}};
  c.add("m2", {"d", "e", "f", "a"}, -1).model = {{"vto", -0.3}, {"kp", 5e-4}, {"gamma", 0.3}, {"lambda", 0.1}};
  return c;
}

TEST(Jacobian, EveryDeviceMatchesFiniteDifferencesInEveryMode) {
  Model model(every_device(), {.tstep = 1e-5, .tstop = 1e-3});
  std::mt19937 random(7);
  std::uniform_real_distribution<double> value(-0.9, 0.9);
  for (int trial = 0; trial < 4; ++trial) {
    Vector x(model.size());
    for (int i = 0; i < model.size(); ++i) x[i] = value(random);
    for (int mask = 0; mask < (1 << model.predicate_count()); mask += 3) {
      padae::Predicates p(model.predicate_count());
      for (int k = 0; k < model.predicate_count(); ++k) p[k] = (mask >> k) & 1;
      SCOPED_TRACE("trial " + std::to_string(trial) + " predicates " + std::to_string(mask));
      expect_jacobians_match_differences(model, x, p);
    }
  }
}

// The devices that say their derivatives depend on the predicates alone: the same Jacobians at
// every (t, x) of a mode.
TEST(Jacobian, DevicesClaimingAConstantJacobianHaveOneInEveryMode) {
  Model model(linear_devices(), {.tstep = 1e-5, .tstop = 1e-3});
  ASSERT_TRUE(model.constant_jacobian());
  std::mt19937 random(11);
  std::uniform_real_distribution<double> value(-0.9, 0.9);
  for (int mask = 0; mask < (1 << model.predicate_count()); ++mask) {
    padae::Predicates p(model.predicate_count());
    for (int k = 0; k < model.predicate_count(); ++k) p[k] = (mask >> k) & 1;
    std::vector<DenseLoad> loads;
    for (int trial = 0; trial < 3; ++trial) {
      Vector x(model.size());
      for (int i = 0; i < model.size(); ++i) x[i] = value(random);
      loads.push_back(evaluate(model, 1e-4 * (1 + value(random)), x, p));
    }
    for (const DenseLoad& load : loads) {
      EXPECT_EQ(load.df, loads.front().df) << "predicates " << mask;
      EXPECT_EQ(load.dq, loads.front().dq) << "predicates " << mask;
    }
  }
  // Junctions, MOSFETs and nonlinear B sources do not claim it.
  EXPECT_FALSE(Model(every_device(), {.tstep = 1e-5, .tstop = 1e-3}).constant_jacobian());
}

TEST(Jacobian, DiodeAcrossItsRegionsAndExponentLimit) {
  CircuitSpec c;
  c.add("d1", {"a", "0"}).model = {{"is", 1e-14}, {"cjo", 1e-12}, {"bv", 10.0}};
  Model model(c, {});
  for (double v : {-12.0, -10.0, -5.0, -0.05, 0.0, 0.3, 0.45, 0.7, 1.2, 3.0}) {
    SCOPED_TRACE(v);
    Vector x(1);
    x << v;
    expect_jacobians_match_differences(model, x, {});
  }
}

}  // namespace
}  // namespace mna::test
