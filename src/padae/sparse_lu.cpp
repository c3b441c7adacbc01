#include "padae/sparse_lu.hpp"

#include <klu.h>

#include <stdexcept>
#include <vector>

namespace padae {

namespace {

// +1 for an even permutation, -1 for an odd one: (-1)^(n - number of cycles).
int permutation_sign(const int* permutation, int n) {
  std::vector<char> seen(static_cast<std::size_t>(n), 0);
  int sign = 1;
  for (int start = 0; start < n; ++start) {
    if (seen[start]) continue;
    int length = 0;
    for (int i = start; !seen[i]; i = permutation[i]) seen[i] = 1, ++length;
    if (length % 2 == 0) sign = -sign;
  }
  return sign;
}

}  // namespace

struct SparseLu::KluState {
  klu_common common;
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  double pivoted_rcond = 0;  // reciprocal condition estimate of the last pivoting factorization
};

SparseLu::SparseLu(const Pattern& pattern) : pattern_(pattern), klu_(new KluState) {
  klu_defaults(&klu_->common);
  klu_->common.halt_if_singular = 1;
  // KLU's C API takes non-const pointers but does not modify the pattern.
  klu_->symbolic = klu_analyze(pattern.size(), const_cast<int*>(pattern.column_starts().data()),
                               const_cast<int*>(pattern.row_indices().data()), &klu_->common);
  if (!klu_->symbolic) {
    delete klu_;
    throw std::runtime_error("KLU could not analyze the sparsity pattern");
  }
}

SparseLu::~SparseLu() {
  release_numeric();
  klu_free_symbolic(&klu_->symbolic, &klu_->common);
  delete klu_;
}

void SparseLu::release_numeric() {
  if (klu_->numeric) klu_free_numeric(&klu_->numeric, &klu_->common);
}

bool SparseLu::factor(const std::vector<double>& values) {
  auto* starts = const_cast<int*>(pattern_.column_starts().data());
  auto* rows = const_cast<int*>(pattern_.row_indices().data());
  auto* data = const_cast<double*>(values.data());
  singular_column_ = -1;
  if (klu_->numeric) {
    // Reuse the pivot order; pivot afresh when the old order has become much worse conditioned
    // than a pivoting factorization was (a mode change can make old pivots tiny).
    if (klu_refactor(starts, rows, data, klu_->symbolic, klu_->numeric, &klu_->common) &&
        klu_rcond(klu_->symbolic, klu_->numeric, &klu_->common) &&
        klu_->common.rcond > 1e-3 * klu_->pivoted_rcond)
      return true;
    release_numeric();
  }
  klu_->numeric = klu_factor(starts, rows, data, klu_->symbolic, &klu_->common);
  if (!klu_->numeric || klu_->common.status == KLU_SINGULAR) {
    singular_column_ = klu_->common.singular_col < pattern_.size()
                           ? static_cast<int>(klu_->common.singular_col)
                           : -1;
    release_numeric();
    return false;
  }
  klu_rcond(klu_->symbolic, klu_->numeric, &klu_->common);
  klu_->pivoted_rcond = klu_->common.rcond;
  return true;
}

// KLU factors P (R^-1 A) Q = L U + F: R a positive row scaling, L unit lower triangular, F
// the off-diagonal blocks (strictly block upper triangular, so no part of the determinant).
int SparseLu::determinant_sign() const {
  if (!klu_->numeric) throw std::logic_error("SparseLu::determinant_sign before a successful factor");
  const int n = pattern_.size();
  const auto* u_diagonal = static_cast<const double*>(klu_->numeric->Udiag);
  int sign = permutation_sign(klu_->numeric->Pnum, n) * permutation_sign(klu_->symbolic->Q, n);
  for (int k = 0; k < n; ++k)
    if (u_diagonal[k] < 0) sign = -sign;
  return sign;
}

void SparseLu::solve(Vector& b) const {
  if (!klu_->numeric) throw std::logic_error("SparseLu::solve before a successful factor");
  klu_solve(klu_->symbolic, klu_->numeric, pattern_.size(), 1, b.data(), &klu_->common);
}

}  // namespace padae
