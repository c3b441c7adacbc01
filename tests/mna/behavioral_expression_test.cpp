// B-source expressions: predicates extracted from conditions and kinks, values for fixed
// predicates, exact gradients.
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.hpp"
#include "mna/behavioral_expression.hpp"

namespace mna::test {
namespace {

using netlist::BinaryOperator;

struct Fixture {
  Unknowns unknowns;
  int a, b;
  Fixture() { a = unknowns.node("a"), b = unknowns.node("b"); }
};

TEST(BehavioralExpression, ComparatorTernaryIsOnePredicate) {
  Fixture fx;
  // v(a) > v(b) ? 5 : -5
  BehavioralExpression e(*conditional(binary(BinaryOperator::greater, voltage("a"), voltage("b")), number(5), number(-5)),
                         fx.unknowns, "b1");
  ASSERT_EQ(e.predicate_count(), 1);
  EXPECT_EQ(e.predicate_label(0), "v(a)>v(b)");
  Vector x(2);
  x << 1.0, 1.5;
  double guard;
  e.guards(0, x, &guard);
  EXPECT_DOUBLE_EQ(guard, -0.5);
  const std::uint8_t on = 1, off = 0;
  double gradient[2];
  EXPECT_DOUBLE_EQ(e.evaluate(0, x, &on, gradient), 5);  // the predicate, not the state, decides
  EXPECT_DOUBLE_EQ(e.evaluate(0, x, &off, gradient), -5);
  EXPECT_DOUBLE_EQ(gradient[0], 0);
}

TEST(BehavioralExpression, LessThanGuardIsRightMinusLeft) {
  Fixture fx;
  BehavioralExpression e(*binary(BinaryOperator::less, voltage("a"), number(2)), fx.unknowns, "b1");
  Vector x(2);
  x << 0.5, 0;
  double guard;
  e.guards(0, x, &guard);
  EXPECT_DOUBLE_EQ(guard, 1.5);
}

TEST(BehavioralExpression, KinksBecomePredicates) {
  Fixture fx;
  // abs(v(a)) + min(v(a), v(b)) + limit(v(b), 0, 1) + u(time - 1)
  auto sum = binary(BinaryOperator::add, call("abs", {voltage("a")}), call("min", {voltage("a"), voltage("b")}));
  sum = binary(BinaryOperator::add, sum, call("limit", {voltage("b"), number(0), number(1)}));
  sum = binary(BinaryOperator::add, sum, call("u", {binary(BinaryOperator::subtract, time(), number(1))}));
  BehavioralExpression e(*sum, fx.unknowns, "b1");
  ASSERT_EQ(e.predicate_count(), 1 + 1 + 2 + 1);
  Vector x(2);
  x << -2.0, 3.0;
  double guards[5];
  e.guards(2.0, x, guards);
  padae::Predicates p(5);
  for (int k = 0; k < 5; ++k) p[k] = guards[k] > 0;
  double gradient[2];
  // |-2| + min(-2, 3) + limit(3, 0, 1) + u(1) = 2 - 2 + 1 + 1
  EXPECT_DOUBLE_EQ(e.evaluate(2.0, x, p.data(), gradient), 2.0);
  EXPECT_DOUBLE_EQ(gradient[0], -1 + 1);  // d|a|/da = -1, d min/da = 1
  EXPECT_DOUBLE_EQ(gradient[1], 0);       // limited
  // u(time - 1): its guard is time - 1 (time crossings are located by root finding too).
  EXPECT_DOUBLE_EQ(guards[4], 1.0);
}

TEST(BehavioralExpression, GradientIsExactForSmoothFunctions) {
  Fixture fx;
  // v(a)^2 * sin(v(b)) / (1 + exp(v(a) - v(b)))
  auto numerator = binary(BinaryOperator::multiply, binary(BinaryOperator::power, voltage("a"), number(2)), call("sin", {voltage("b")}));
  auto denominator = binary(BinaryOperator::add, number(1), call("exp", {voltage("a", "b")}));
  BehavioralExpression e(*binary(BinaryOperator::divide, numerator, denominator), fx.unknowns, "b1");
  const double a = 0.7, b = -0.4;
  Vector x(2);
  x << a, b;
  double gradient[2];
  const double value = e.evaluate(0, x, nullptr, gradient);
  const double den = 1 + std::exp(a - b);
  EXPECT_NEAR(value, a * a * std::sin(b) / den, 1e-15);
  const double dda = 2 * a * std::sin(b) / den - a * a * std::sin(b) * std::exp(a - b) / (den * den);
  const double ddb = a * a * std::cos(b) / den + a * a * std::sin(b) * std::exp(a - b) / (den * den);
  EXPECT_NEAR(gradient[0], dda, 1e-14);
  EXPECT_NEAR(gradient[1], ddb, 1e-14);
}

// Where ngspice's functions are infinite, its stand-ins: a zero divisor is 1e-32, ln(0) is
// -1e99; and sqrt's infinite slope at 0 is left out, as x^0.5's.
TEST(BehavioralExpression, SingularPointsHaveNgspicesFiniteStandIns) {
  Fixture fx;
  Vector x = Vector::Zero(2);
  double gradient[1];
  auto at_zero = [&](netlist::ExpressionPtr e) {
    const double value = BehavioralExpression(*e, fx.unknowns, "b1").evaluate(0, x, nullptr, gradient);
    return std::pair{value, gradient[0]};
  };
  EXPECT_EQ(at_zero(call("sqrt", {voltage("a")})), std::pair(0.0, 0.0));
  EXPECT_EQ(at_zero(call("ln", {voltage("a")})), std::pair(-1e99, 0.0));
  EXPECT_EQ(at_zero(call("log10", {voltage("a")})), std::pair(-1e99, 0.0));
  const auto [quotient, slope] = at_zero(binary(BinaryOperator::divide, number(2), voltage("a")));
  EXPECT_DOUBLE_EQ(quotient, 2e32);
  EXPECT_DOUBLE_EQ(slope, -2e64);
  x[0] = 4;  // elsewhere the functions themselves
  EXPECT_EQ(at_zero(call("sqrt", {voltage("a")})), std::pair(2.0, 0.25));
  EXPECT_EQ(at_zero(binary(BinaryOperator::divide, number(2), voltage("a"))), std::pair(0.5, -0.125));
}

// ngspice 39's PTpower: |x|^y for every y, so (-2)^3 = 8 (pwr is the signed power).
TEST(BehavioralExpression, PowerIsOfTheMagnitudeAsInNgspice) {
  Fixture fx;
  Vector x(2);
  x << -2, 3;
  double gradient[2];
  BehavioralExpression cube(*binary(BinaryOperator::power, voltage("a"), voltage("b")), fx.unknowns, "b1");
  EXPECT_DOUBLE_EQ(cube.evaluate(0, x, nullptr, gradient), 8);
  EXPECT_DOUBLE_EQ(gradient[0], -12);                 // d|a|^b/da = b |a|^(b-1) sgn(a)
  EXPECT_DOUBLE_EQ(gradient[1], 8 * std::log(2.0));  // d|a|^b/db = |a|^b ln|a|
  BehavioralExpression root(*call("pow", {voltage("a"), number(0.5)}), fx.unknowns, "b1");
  EXPECT_DOUBLE_EQ(root.evaluate(0, x, nullptr, nullptr), std::sqrt(2.0));
}

TEST(BehavioralExpression, DeadBranchNeverPoisonsTheGradient) {
  Fixture fx;
  // v(a) > 0 ? sqrt(v(a)) : 0, evaluated at v(a) < 0 with the predicate off
  BehavioralExpression e(*conditional(binary(BinaryOperator::greater, voltage("a"), number(0)), call("sqrt", {voltage("a")}), number(0)),
                         fx.unknowns, "b1");
  Vector x(2);
  x << -1, 0;
  const std::uint8_t off = 0;
  double gradient[1];
  EXPECT_EQ(e.evaluate(0, x, &off, gradient), 0);
  EXPECT_EQ(gradient[0], 0);
}

// A mode past its crossed guard only locates the crossing: there sqrt is continued below 0
// (-sqrt(-x)), so that abs's branch reaching the domain edge with its guard stays evaluable.
// Nowhere else: a negative argument without a crossed guard is outside the domain.
TEST(BehavioralExpression, SqrtIsContinuedBelowZeroOnlyPastACrossedGuard) {
  Fixture fx;
  Vector x(2);
  x << -0.25, 1;
  double gradient[2];
  BehavioralExpression root_of_abs(*call("sqrt", {call("abs", {voltage("a")})}), fx.unknowns, "b1");
  const std::uint8_t positive_branch = 1, negative_branch = 0;
  EXPECT_DOUBLE_EQ(root_of_abs.evaluate(0, x, &positive_branch, gradient), -0.5);  // guard a > 0 crossed
  EXPECT_DOUBLE_EQ(gradient[0], 1);
  EXPECT_DOUBLE_EQ(root_of_abs.evaluate(0, x, &negative_branch, gradient), 0.5);  // the live mode
  EXPECT_DOUBLE_EQ(gradient[0], -1);
  BehavioralExpression root(*call("sqrt", {voltage("a")}), fx.unknowns, "b1");
  EXPECT_FALSE(std::isfinite(root.evaluate(0, x, nullptr, gradient)));
  BehavioralExpression root_and_condition(
      *binary(BinaryOperator::add, call("sqrt", {voltage("a")}),
              conditional(binary(BinaryOperator::greater, voltage("b"), number(0)), number(1), number(0))),
      fx.unknowns, "b1");
  const std::uint8_t b_positive = 1;  // its guard, b = 1, not crossed
  EXPECT_FALSE(std::isfinite(root_and_condition.evaluate(0, x, &b_positive, gradient)));
}

TEST(BehavioralExpression, EqualityUsesTwoPredicates) {
  Fixture fx;
  BehavioralExpression e(*conditional(binary(BinaryOperator::equal, voltage("a"), voltage("b")), number(1), number(0)), fx.unknowns, "b1");
  EXPECT_EQ(e.predicate_count(), 2);
  Vector x(2);
  x << 1, 1;
  const std::uint8_t neither[2] = {0, 0}, above[2] = {1, 0};
  EXPECT_EQ(e.evaluate(0, x, neither, nullptr), 1);
  EXPECT_EQ(e.evaluate(0, x, above, nullptr), 0);
}

// A predicate holds where its guard is positive; at equality (a source resting at the threshold)
// >= and <= are true, > and < false, as in ngspice.
TEST(BehavioralExpression, NonStrictComparisonsHoldAtEquality) {
  Fixture fx;
  Vector x(2);
  x << 1, 1;
  auto value_at = [&](BinaryOperator op, const Vector& at) {
    BehavioralExpression e(*conditional(binary(op, voltage("a"), voltage("b")), number(1), number(0)), fx.unknowns, "b1");
    std::vector<double> guards(static_cast<std::size_t>(e.predicate_count()));
    e.guards(0, at, guards.data());
    padae::Predicates p(guards.size());
    for (std::size_t k = 0; k < guards.size(); ++k) p[k] = guards[k] > 0;
    return e.evaluate(0, at, p.data(), nullptr);
  };
  EXPECT_EQ(value_at(BinaryOperator::greater_equal, x), 1);
  EXPECT_EQ(value_at(BinaryOperator::less_equal, x), 1);
  EXPECT_EQ(value_at(BinaryOperator::greater, x), 0);
  EXPECT_EQ(value_at(BinaryOperator::less, x), 0);
  Vector above(2);
  above << 2, 1;
  EXPECT_EQ(value_at(BinaryOperator::greater_equal, above), 1);
  EXPECT_EQ(value_at(BinaryOperator::less_equal, above), 0);
  Vector below(2);
  below << 0, 1;
  EXPECT_EQ(value_at(BinaryOperator::greater_equal, below), 0);
  EXPECT_EQ(value_at(BinaryOperator::less_equal, below), 1);
}

TEST(BehavioralExpression, ConstantGradientOnlyWhereAffineInEveryMode) {
  Fixture fx;
  auto constant_gradient = [&](netlist::ExpressionPtr e) { return BehavioralExpression(*e, fx.unknowns, "b1").constant_gradient(); };
  auto add = [](auto l, auto r) { return binary(BinaryOperator::add, l, r); };
  auto times = [](auto l, auto r) { return binary(BinaryOperator::multiply, l, r); };
  auto over = [](auto l, auto r) { return binary(BinaryOperator::divide, l, r); };
  // Affine with constant coefficients, forcing terms of time, conditions choosing among them.
  EXPECT_TRUE(constant_gradient(add(times(number(2), voltage("a")), over(voltage("b"), number(3)))));
  EXPECT_TRUE(constant_gradient(add(voltage("a"), call("sin", {times(number(6.28), time())}))));
  EXPECT_TRUE(constant_gradient(conditional(binary(BinaryOperator::greater, voltage("a"), voltage("b")), number(5), number(-5))));
  EXPECT_TRUE(constant_gradient(call("abs", {voltage("a", "b")})));
  EXPECT_TRUE(constant_gradient(times(over(time(), number(2)), call("exp", {time()}))));
  // Products and functions of unknowns, and coefficients varying in time.
  EXPECT_FALSE(constant_gradient(times(voltage("a"), voltage("b"))));
  EXPECT_FALSE(constant_gradient(times(voltage("a"), time())));
  EXPECT_FALSE(constant_gradient(over(number(1), voltage("a"))));
  EXPECT_FALSE(constant_gradient(over(voltage("a"), time())));
  EXPECT_FALSE(constant_gradient(call("exp", {voltage("a")})));
  EXPECT_FALSE(constant_gradient(binary(BinaryOperator::power, voltage("a"), number(2))));
  EXPECT_FALSE(constant_gradient(conditional(binary(BinaryOperator::greater, voltage("a"), number(0)), voltage("a"),
                                             call("tanh", {voltage("b")}))));
}

TEST(BehavioralExpression, UnknownReferencesAreErrors) {
  Fixture fx;
  EXPECT_THROW(BehavioralExpression(*voltage("nowhere"), fx.unknowns, "b1"), ModelError);
  EXPECT_THROW(BehavioralExpression(*current("v9"), fx.unknowns, "b1"), ModelError);
  EXPECT_THROW(BehavioralExpression(*call("gamma", {number(1)}), fx.unknowns, "b1"), ModelError);
}

}  // namespace
}  // namespace mna::test
