// Sparsity pattern of the Jacobians, declared once by a system so that the sparse LU
// analyzes it once.
#pragma once

#include <span>
#include <utility>
#include <vector>

namespace padae {

// A square compressed-column pattern. Both Jacobians of a system (df/dx and dq/dx) store
// their values on this one pattern, so the Newton matrix df/dx + cj dq/dx is formed by adding
// two value arrays. The diagonal is always present (the integrator needs it for auxiliary rows).
class Pattern {
 public:
  Pattern() = default;
  // entries: (row, column) pairs, in any order, duplicates allowed.
  Pattern(int size, std::span<const std::pair<int, int>> entries);

  int size() const { return size_; }
  int nonzeros() const { return static_cast<int>(row_indices_.size()); }
  // Position of (row, column) in a value array; throws std::out_of_range if not in the pattern.
  int index(int row, int column) const;
  // Position of (row, column), or -1.
  int find(int row, int column) const;

  const std::vector<int>& column_starts() const { return column_starts_; }
  const std::vector<int>& row_indices() const { return row_indices_; }

 private:
  int size_ = 0;
  std::vector<int> column_starts_{0};
  std::vector<int> row_indices_;
};

}  // namespace padae
