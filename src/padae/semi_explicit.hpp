// The paper's semi-explicit forms (3) and (5), expressed directly:
//     x' = rhs(t, x, y, p) (+ X p'),   0 = g(t, x, y, p),   p = P(t, x, y)
// A model lists its unknowns' kinds and writes, row by row, rhs_i for differential unknowns
// and g_i for algebraic ones; the adapter turns that into the charge form with q_i = x_i.
// Derivatives of the equations may be given (equation_jacobian) or left to finite differences.
#pragma once

#include <utility>
#include <vector>

#include "padae/system.hpp"

namespace padae {

class SemiExplicitSystem : public System {
 public:
  // entries: the (row, column) non-zeros of d(equations)/dz; empty means dense.
  SemiExplicitSystem(std::vector<UnknownKind> kinds, std::vector<std::pair<int, int>> entries = {});

  // out[i] = rhs_i for differential rows, g_i for algebraic rows (auxiliary rows: ignored).
  virtual EvalStatus equations(double t, const Vector& z, const Predicates& p, Vector& out) = 0;
  // d(equations)/dz on pattern() (values arrive zeroed); false: use finite differences.
  virtual bool equation_jacobian(double t, const Vector& z, const Predicates& p,
                                 std::vector<double>& values) {
    (void)t, (void)z, (void)p, (void)values;
    return false;
  }
  virtual bool has_equation_jacobian() const { return false; }

  int size() const override { return static_cast<int>(kinds_.size()); }
  UnknownKind kind(int unknown) const override { return kinds_[unknown]; }
  const Pattern& pattern() const override { return pattern_; }
  bool analytic_jacobian() const override { return has_equation_jacobian(); }
  EvalStatus load(double t, const Vector& x, const Predicates& p, Load& out) override;

 private:
  std::vector<UnknownKind> kinds_;
  Pattern pattern_;
  std::vector<int> diagonal_;
  Vector equations_;
  std::vector<double> jacobian_;
};

}  // namespace padae
