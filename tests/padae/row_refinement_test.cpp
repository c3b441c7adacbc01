#include "padae/row_refinement.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

namespace padae {
namespace {

using Row = RowRefinement::Row;

// Rows on a grid over a step [0, 1] of one unknown, as the writer asks for them: each from the
// polynomial, the refinement's interpolant or a solve of its own.
struct Written {
  int solves = 0;         // the refinement's checks and the rows solved
  int solved_rows = 0;
  int polynomial_rows = 0;
  double worst_error = 0;  // of the rows, in units of the tolerance
};

Written write_rows(const std::function<double(double)>& solution, const std::function<double(double)>& polynomial,
                   double tolerance, int rows) {
  Written written;
  const std::vector<int> unknowns{0};
  const Vector inverse_weight = Vector::Constant(1, 1 / tolerance);
  auto polynomial_at = [&](double t, Vector& out) { out = Vector::Constant(1, polynomial(t)); };
  auto solve = [&](double t, const Vector&) -> std::optional<Vector> {
    ++written.solves;
    return Vector::Constant(1, solution(t));
  };
  RowRefinement refinement(polynomial_at, solve);
  refinement.reset(7, 0.0, 1.0);
  for (int k = 1; k <= rows; ++k) {
    const double t = static_cast<double>(k) / rows;
    Vector value(1);
    switch (refinement.row(t, unknowns, inverse_weight)) {
      case Row::polynomial:
        ++written.polynomial_rows;
        polynomial_at(t, value);
        break;
      case Row::interpolated:
        polynomial_at(t, value);
        refinement.interpolate(t, unknowns, value);
        break;
      case Row::solved:
        ++written.solves;
        ++written.solved_rows;
        value[0] = solution(t);
        break;
    }
    written.worst_error = std::max(written.worst_error, std::abs(value[0] - solution(t)) / tolerance);
  }
  return written;
}

TEST(RowRefinement, ThePolynomialServesWhereItPredictsTheMidpoint) {
  auto solution = [](double t) { return std::exp(-t); };
  auto polynomial = [&](double t) { return solution(t) + 0.5e-6 * t * (1 - t); };
  const Written written = write_rows(solution, polynomial, 1e-6, 40);
  EXPECT_EQ(written.polynomial_rows, 40);
  EXPECT_EQ(written.solves, 1);  // the midpoint's check alone
  EXPECT_LE(written.worst_error, 1.0);
}

// A polynomial through points from before a junction turned off bulges between the step's
// ends (by 1e4 tolerances here) while the solution stays smooth: the quadratics through the
// solution serve once their nodes are close enough: a quadratic's error at a check is about
// |x'''| h^3 / 16 for nodes h apart, 1.5e-6 at h = 1/16 (x''' <= 0.1 here), so the checks
// reach down to sixteenths of the step at most.
TEST(RowRefinement, AFarPolynomialGivesWayToTheSolutionsQuadratics) {
  auto solution = [](double t) { return 10 + 0.1 * std::sin(t); };
  auto polynomial = [&](double t) { return solution(t) + 1e-2 * t * (1 - t) * (2 - t); };
  const Written written = write_rows(solution, polynomial, 1e-6, 64);
  EXPECT_EQ(written.polynomial_rows, 0);
  EXPECT_LE(written.worst_error, 1.0);
  EXPECT_LE(written.solves, 1 + 2 + 4 + 8 + 16 + 32);  // against 65 with every row solved
}

// A polynomial of the solution's shape, off by a few tolerances: it plus the quadratic of its
// deviation is exact here, and the halves' two checks certify it.
TEST(RowRefinement, ANearPolynomialIsCorrectedByItsDeviationsQuadratic) {
  auto solution = [](double t) { return std::cos(3 * t); };
  auto polynomial = [&](double t) { return solution(t) + 5e-6 * t * (1 - t); };
  const Written written = write_rows(solution, polynomial, 1e-6, 64);
  EXPECT_EQ(written.solves, 3);
  EXPECT_LE(written.worst_error, 1e-6);
}

// A junction turning on inside the step: the solution has a kink at t = 0.3. The intervals
// around it are split until they hold too few rows to check; their rows are solved.
TEST(RowRefinement, RowsNearAKinkAreSolved) {
  auto solution = [](double t) { return t < 0.3 ? 0.0 : (t - 0.3); };
  auto polynomial = [](double t) { return 0.7 * t; };
  const Written written = write_rows(solution, polynomial, 1e-4, 64);
  EXPECT_LE(written.worst_error, 1.0);
  EXPECT_GT(written.solved_rows, 0);
  EXPECT_LE(written.solved_rows, 8);
  EXPECT_LT(written.solves, 40);
}

TEST(RowRefinement, WithoutASolutionAtTheMidpointEveryRowIsSolved) {
  const std::vector<int> unknowns{0};
  auto polynomial = [](double t, Vector& out) { out = Vector::Constant(1, t); };
  int solves = 0;
  auto no_solution = [&](double, const Vector&) -> std::optional<Vector> {
    ++solves;
    return std::nullopt;
  };
  RowRefinement refinement(polynomial, no_solution);
  refinement.reset(1, 0.0, 1.0);
  for (double t : {0.1, 0.4, 0.6, 0.9}) EXPECT_EQ(refinement.row(t, unknowns, Vector::Ones(1)), Row::solved);
  EXPECT_EQ(solves, 1);
}

}  // namespace
}  // namespace padae
