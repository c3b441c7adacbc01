#include "padae/root_finder.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace padae {
namespace {

TEST(RootFinder, LocatesASingleSmoothCrossingToTheTolerance) {
  // guard(t) = cos(t) - 0.5 falls through zero at t = pi/3.
  auto guards = [](double t, Vector& out) {
    out.resize(1);
    out[0] = std::cos(t) - 0.5;
    return true;
  };
  Vector left(1), right(1);
  guards(0.0, left);
  guards(2.0, right);
  const double tolerance = 1e-14;
  Crossing crossing = locate_first_crossing(guards, Predicates{1}, 0.0, left, 2.0, right, tolerance);
  const double exact = std::acos(0.5);
  EXPECT_LE(crossing.t_right - crossing.t_left, tolerance);
  EXPECT_LE(crossing.t_left, exact + 1e-15);
  EXPECT_GE(crossing.t_right, exact - 1e-15);
  EXPECT_LE(crossing.guards_right[0], 0.0);  // the new side holds at t_right
  EXPECT_LT(crossing.evaluations, 20);     // Illinois converges superlinearly
}

TEST(RootFinder, FindsTheEarliestOfSeveralCrossings) {
  // Three guards cross at 0.7, 0.3 (rising) and 0.5; the earliest, 0.3, must be found even
  // though the first guard's crossing dominates at the right end.
  auto guards = [](double t, Vector& out) {
    out.resize(3);
    out[0] = 0.7 - t;
    out[1] = std::pow(t, 3) - 0.027;
    out[2] = 0.5 - t;
    return true;
  };
  Vector left(3), right(3);
  guards(0.0, left);
  guards(1.0, right);
  Crossing crossing = locate_first_crossing(guards, Predicates{1, 0, 1}, 0.0, left, 1.0, right, 1e-13);
  EXPECT_NEAR(crossing.t_right, 0.3, 1e-13);
  EXPECT_GT(crossing.guards_right[1], 0.0);
  EXPECT_GT(crossing.guards_right[0], 0.0);  // the others have not crossed yet
  EXPECT_GT(crossing.guards_right[2], 0.0);
}

TEST(RootFinder, ACrossingRightAtTheLeftEndIsFound) {
  // Round-off left the guard on the wrong side at the left end (a predicate that flips back
  // right after an event): the crossing is at the left end.
  auto guards = [](double t, Vector& out) {
    out.resize(1);
    out[0] = t - 1.0 + 1e-17;
    return true;
  };
  Vector left(1), right(1);
  guards(1.0, left);
  guards(2.0, right);
  Crossing crossing = locate_first_crossing(guards, Predicates{0}, 1.0, left, 2.0, right, 1e-12);
  EXPECT_NEAR(crossing.t_right, 1.0, 1e-12);
}

TEST(RootFinder, ALinearGuardIsBracketedInThreeEvaluations) {
  // A gate drive's ramp between the samples at its corners: regula falsi's first trial is the
  // root to round-off, and a trial a tenth of the tolerance beside it closes the bracket (a
  // third where round-off put the first on the wrong side). The bracket used to shrink by a
  // tenth of its width per trial from there: 12 evaluations.
  auto guards = [](double t, Vector& out) {
    out.resize(1);
    out[0] = 2.5 - 5e8 * t;
    return true;
  };
  Vector left(1), right(1);
  guards(4.5e-9, left);
  guards(1.45e-8, right);
  const double tolerance = 100 * 2.2e-16 * 1e-5;
  Crossing crossing = locate_first_crossing(guards, Predicates{1}, 4.5e-9, left, 1.45e-8, right, tolerance);
  EXPECT_LE(crossing.t_right - crossing.t_left, tolerance);
  EXPECT_LE(crossing.t_left, 5e-9);
  EXPECT_GE(crossing.t_right, 5e-9);
  EXPECT_LE(crossing.evaluations, 3);
}

TEST(RootFinder, SteepGuardNeedsFewEvaluations) {
  // A guard with a huge dynamic range (exp) defeats plain regula falsi; Illinois does not stall.
  auto guards = [](double t, Vector& out) {
    out.resize(1);
    out[0] = std::exp(20 * t) - std::exp(10.0);
    return true;
  };
  Vector left(1), right(1);
  guards(0.0, left);
  guards(1.0, right);
  Crossing crossing = locate_first_crossing(guards, Predicates{0}, 0.0, left, 1.0, right, 1e-14);
  EXPECT_NEAR(crossing.t_right, 0.5, 2e-14);
  EXPECT_LT(crossing.evaluations, 40);
}

}  // namespace
}  // namespace padae
