// Locating the first sign change of several guard functions on an interval: the Illinois
// variant of regula falsi, applied to all guards at once (as in IDA's root finding), so the
// earliest crossing is found even when several guards change sign in the same step.
#pragma once

#include <functional>

#include "padae/system.hpp"

namespace padae {

struct Crossing {
  double t_left;       // guards still on the old side here
  double t_right;      // the earliest crossing lies in (t_left, t_right]; the new side holds here
  Vector guards_right;  // guard values at t_right
  int evaluations = 0;
  bool ok = true;      // false when a guard evaluation failed
};

// guards(t, out) evaluates the guard vector at t. `old_side[k]` is predicate k on the left end
// (guard > 0 <=> true); guards_left may be on the wrong side by round-off (it is then treated
// as zero). Predicate k has crossed where (guard_k > 0) != old_side[k]; at least one guard must
// have crossed at t_right. Stops when t_right - t_left <= tolerance.
Crossing locate_first_crossing(const std::function<bool(double, Vector&)>& guards,
                               const Predicates& old_side, double t_left,
                               const Vector& guards_left, double t_right,
                               const Vector& guards_right, double tolerance);

}  // namespace padae
