// A B-source expression compiled into a tape: its value and exact gradient (reverse-mode
// differentiation) for fixed predicates, and a guard for every condition inside it.
//
// Conditions become predicates (predicate-dae.md, section 3): each comparison a > b is one
// predicate with guard a - b (a < b: b - a; a >= b is not b > a, true on the boundary; == and !=
// use the two predicates a > b and b > a). Kinks lower to ternaries on predicates:
// abs(x) = x > 0 ? x : -x, min, max, u, uramp, sgn, limit, pwr. A number used as a condition
// means "non-zero". For fixed predicates the expression is smooth; both branches of a ternary
// are evaluated (their guards exist whatever the predicate), but only the live one counts.
// floor and ceil are piecewise constant with unbounded jump count: no predicate, zero slope.
// `^`, `**` and pow(x, y) follow ngspice 39: |x|^y, also for a whole y ((-2)^3 = 8); pwr(x, y)
// is sgn(x) |x|^y. In a mode past one of its crossed guards (used only to locate the crossing)
// sqrt is continued below 0 as -sqrt(-x): abs's live branch reaches sqrt's domain edge together
// with its guard.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "mna/device.hpp"
#include "netlist/expression.hpp"

namespace mna {

class BehavioralExpression {
 public:
  // Resolves v(node) and i(element) against the unknowns; throws ModelError for an unknown
  // node, an element without a branch current, an unresolved parameter or function.
  BehavioralExpression(const netlist::Expression& expression, const Unknowns& unknowns,
                       const std::string& element);

  // Distinct unknowns the expression reads, in the order of gradient entries.
  const std::vector<int>& inputs() const { return inputs_; }
  int predicate_count() const { return static_cast<int>(predicate_labels_.size()); }
  const std::string& predicate_label(int k) const { return predicate_labels_[k]; }

  // Value at (t, x) with predicates p[0..predicate_count()); gradient[k] = d value / d x[inputs()[k]].
  double evaluate(double t, const Vector& x, const std::uint8_t* p, double* gradient) const;
  // guard_k(t, x) for every predicate; conditions nested inside conditions use their own guards.
  void guards(double t, const Vector& x, double* out) const;
  // Whether the gradient depends on the predicates alone (the expression is affine in the
  // unknowns in every mode, with coefficients that do not vary in time).
  bool constant_gradient() const { return constant_gradient_; }

 private:
  enum class Op : std::uint8_t {
    constant, input, time, negate, add, subtract, multiply, divide, power, greater,
    logical_not, logical_and, logical_or, select, exp, log, log10, sqrt, sin, cos, tan, atan,
    sinh, cosh, tanh, floor, ceil, atan2,
  };
  struct Instruction {
    Op op;
    int a = -1, b = -1, c = -1;  // operand instructions
    double constant = 0;
    int index = -1;  // input: position in inputs_; greater: predicate
  };

  int compile(const netlist::Expression& e, const Unknowns& unknowns);
  int compile_condition(const netlist::Expression& e, const Unknowns& unknowns);
  int emit(Instruction instruction);
  int constant(double value) { return emit({.op = Op::constant, .constant = value}); }
  int greater(int a, int b, std::string label);
  int input(int unknown);
  // Forward sweep: values and local partials. With p null, conditions follow their guards
  // (written to guard_out). With p, whether a guard is past its crossing (on the other side of
  // its predicate) goes to past_a_guard_; with continued, sqrt is continued below 0 as
  // -sqrt(-x).
  void forward(double t, const Vector& x, const std::uint8_t* p, double* guard_out, bool continued = false) const;
  bool find_constant_gradient() const;

  std::string element_;
  std::vector<Instruction> tape_;
  std::vector<int> inputs_;
  std::vector<std::string> predicate_labels_;
  bool constant_gradient_ = false;
  mutable bool past_a_guard_ = false;
  mutable std::vector<double> values_, adjoints_;
  mutable std::vector<std::array<double, 3>> partials_;
};

}  // namespace mna
