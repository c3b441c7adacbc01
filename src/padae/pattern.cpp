#include "padae/pattern.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace padae {

Pattern::Pattern(int size, std::span<const std::pair<int, int>> entries) : size_(size) {
  std::vector<std::pair<int, int>> by_column;  // (column, row)
  by_column.reserve(entries.size() + static_cast<std::size_t>(size));
  for (auto [row, column] : entries) {
    if (row < 0 || row >= size || column < 0 || column >= size)
      throw std::out_of_range("pattern entry (" + std::to_string(row) + ", " +
                              std::to_string(column) + ") outside a " + std::to_string(size) +
                              "-square matrix");
    by_column.emplace_back(column, row);
  }
  for (int i = 0; i < size; ++i) by_column.emplace_back(i, i);
  std::sort(by_column.begin(), by_column.end());
  by_column.erase(std::unique(by_column.begin(), by_column.end()), by_column.end());

  column_starts_.assign(static_cast<std::size_t>(size) + 1, 0);
  row_indices_.reserve(by_column.size());
  for (auto [column, row] : by_column) {
    ++column_starts_[static_cast<std::size_t>(column) + 1];
    row_indices_.push_back(row);
  }
  for (int column = 0; column < size; ++column)
    column_starts_[column + 1] += column_starts_[column];
}

int Pattern::find(int row, int column) const {
  if (column < 0 || column >= size_) return -1;
  auto begin = row_indices_.begin() + column_starts_[column];
  auto end = row_indices_.begin() + column_starts_[column + 1];
  auto it = std::lower_bound(begin, end, row);
  return (it != end && *it == row) ? static_cast<int>(it - row_indices_.begin()) : -1;
}

int Pattern::index(int row, int column) const {
  int position = find(row, column);
  if (position < 0)
    throw std::out_of_range("(" + std::to_string(row) + ", " + std::to_string(column) +
                            ") is not in the declared sparsity pattern");
  return position;
}

}  // namespace padae
