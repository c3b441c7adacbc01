// Sparse LU of matrices on a fixed Pattern, by KLU: the pattern is analyzed once; later
// factorizations reuse the pivot order (klu_refactor) while it stays numerically sound.
#pragma once

#include <vector>

#include "padae/pattern.hpp"
#include "padae/system.hpp"

namespace padae {

class SparseLu {
 public:
  explicit SparseLu(const Pattern& pattern);
  ~SparseLu();
  SparseLu(const SparseLu&) = delete;
  SparseLu& operator=(const SparseLu&) = delete;

  // Factorizes the matrix with these values on the pattern. False when it is singular;
  // singular_column() then names a column KLU could not pivot.
  bool factor(const std::vector<double>& values);
  // Solves A z = b in place.
  void solve(Vector& b) const;
  int singular_column() const { return singular_column_; }
  // The sign (+1 or -1) of the determinant of the matrix last factored.
  int determinant_sign() const;

 private:
  void release_numeric();

  const Pattern& pattern_;
  struct KluState;
  KluState* klu_;
  int singular_column_ = -1;
};

}  // namespace padae
