#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "padae/pattern.hpp"
#include "padae/sparse_lu.hpp"

namespace padae {
namespace {

TEST(Pattern, CompressedColumnsWithDiagonalAndNoDuplicates) {
  std::vector<std::pair<int, int>> entries{{2, 0}, {0, 1}, {2, 0}, {1, 2}};
  Pattern pattern(3, entries);
  EXPECT_EQ(pattern.nonzeros(), 6);  // 3 off-diagonal (one duplicate) + 3 diagonal
  EXPECT_EQ(pattern.column_starts(), (std::vector<int>{0, 2, 4, 6}));
  EXPECT_EQ(pattern.row_indices(), (std::vector<int>{0, 2, 0, 1, 1, 2}));
  EXPECT_EQ(pattern.index(2, 0), 1);
  EXPECT_EQ(pattern.find(1, 0), -1);
  EXPECT_THROW(pattern.index(1, 0), std::out_of_range);
  EXPECT_THROW(Pattern(2, std::vector<std::pair<int, int>>{{0, 2}}), std::out_of_range);
}

TEST(SparseLu, SolvesAgainstDenseLuAndRefactorsWithNewValues) {
  const int n = 40;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::vector<std::pair<int, int>> entries;
  for (int i = 0; i < n; ++i) {
    entries.emplace_back(i, (i + 1) % n);
    entries.emplace_back((i + 3) % n, i);
  }
  Pattern pattern(n, entries);
  SparseLu lu(pattern);
  for (int round = 0; round < 3; ++round) {
    std::vector<double> values(static_cast<std::size_t>(pattern.nonzeros()));
    Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
    for (int column = 0; column < n; ++column)
      for (int k = pattern.column_starts()[column]; k < pattern.column_starts()[column + 1]; ++k) {
        int row = pattern.row_indices()[k];
        values[k] = uniform(random) + (row == column ? 4.0 : 0.0);
        dense(row, column) = values[k];
      }
    ASSERT_TRUE(lu.factor(values));
    Vector b = Vector::NullaryExpr(n, [&](Eigen::Index) { return uniform(random); });
    Vector expected = dense.partialPivLu().solve(b);
    lu.solve(b);
    EXPECT_LT((b - expected).cwiseAbs().maxCoeff(), 1e-12);
  }
}

// Random sparse matrices, reducible (a lower-triangular coupling makes several diagonal blocks)
// and with diagonals of either sign, so that pivoting and the block order both permute.
TEST(SparseLu, DeterminantSignAgreesWithDenseLu) {
  const int n = 30;
  std::mt19937 random(11);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::uniform_int_distribution<int> any_row(0, n - 1);
  std::vector<std::pair<int, int>> entries;
  for (int column = 0; column < n; ++column) {
    entries.emplace_back(any_row(random), column);
    const int below = column + 1 + any_row(random) % 3;
    if (below < n) entries.emplace_back(below, column);
    if (column % 5 != 4) entries.emplace_back(column, column + 1 < n ? column + 1 : 0);
  }
  Pattern pattern(n, entries);
  SparseLu lu(pattern);
  int negative = 0, compared = 0;
  for (int round = 0; round < 40; ++round) {
    std::vector<double> values(static_cast<std::size_t>(pattern.nonzeros()));
    Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
    for (int column = 0; column < n; ++column)
      for (int k = pattern.column_starts()[column]; k < pattern.column_starts()[column + 1]; ++k) {
        values[k] = uniform(random);
        dense(pattern.row_indices()[k], column) = values[k];
      }
    const double determinant = dense.fullPivLu().determinant();
    if (!lu.factor(values) || std::abs(determinant) < 1e-12) continue;
    ++compared;
    negative += determinant < 0;
    EXPECT_EQ(lu.determinant_sign(), determinant > 0 ? 1 : -1) << "round " << round;
  }
  EXPECT_GT(compared, 30);
  EXPECT_GT(negative, 5);
  EXPECT_LT(negative, compared - 5);
}

TEST(SparseLu, ReportsASingularColumn) {
  // Column 1 is all zero: no pivot can be found there.
  std::vector<std::pair<int, int>> entries{{0, 1}, {1, 0}};
  Pattern pattern(3, entries);
  std::vector<double> values(static_cast<std::size_t>(pattern.nonzeros()), 0.0);
  values[pattern.index(0, 0)] = 1;
  values[pattern.index(1, 0)] = 2;
  values[pattern.index(2, 2)] = 1;
  SparseLu lu(pattern);
  EXPECT_FALSE(lu.factor(values));
  EXPECT_EQ(lu.singular_column(), 1);
}

}  // namespace
}  // namespace padae
