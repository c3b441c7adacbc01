#include "padae/root_finder.hpp"

#include <cmath>

namespace padae {

namespace {

bool crossed(double guard, std::uint8_t old_side) { return (guard > 0) != (old_side != 0); }

// The left-end value as the root finder sees it: on the old side by definition.
double on_old_side(double guard, std::uint8_t old_side) {
  return crossed(guard, old_side) ? 0.0 : guard;
}

}  // namespace

Crossing locate_first_crossing(const std::function<bool(double, Vector&)>& guards,
                               const Predicates& old_side, double t_left,
                               const Vector& guards_left, double t_right,
                               const Vector& guards_right, double tolerance) {
  const int count = static_cast<int>(old_side.size());
  Crossing result{t_left, t_right, guards_right};
  Vector low(count);
  for (int k = 0; k < count; ++k) low[k] = on_old_side(guards_left[k], old_side[k]);
  Vector& high = result.guards_right;
  Vector middle(count);

  // The guard whose crossing looks nearest the left end (largest fraction of the interval
  // from the right end, by linear interpolation) steers the next trial point.
  auto steering_guard = [&](const Vector& values) {
    int best = -1;
    double best_fraction = -1;
    for (int k = 0; k < count; ++k) {
      if (!crossed(values[k], old_side[k])) continue;
      double span = values[k] - low[k];
      double fraction = span != 0 ? std::abs(values[k] / span) : 1.0;
      if (fraction > best_fraction) best_fraction = fraction, best = k;
    }
    return best;
  };

  int steer = steering_guard(high);
  double weight = 1;  // Illinois: the retained end's value is down-weighted when it repeats
  int side = 0, previous_side = 0;
  bool nudged = false;  // the last trial point was moved inward from an end
  while (result.t_right - result.t_left > tolerance && steer >= 0) {
    if (previous_side != 0 && side == previous_side)
      weight = side == 2 ? weight * 2 : weight * 0.5;
    else
      weight = 1;
    double width = result.t_right - result.t_left;
    double denominator = high[steer] - weight * low[steer];
    double t = denominator != 0 ? result.t_right - width * high[steer] / denominator
                                : result.t_left + 0.5 * width;
    // A trial point within half the tolerance of an end moves inward, so the bracket always
    // shrinks: by a tenth of the tolerance when the last one did not (the root is most likely
    // right there, found from the other side: this trial then brackets it well within the
    // tolerance), else by a tenth of the width (that guess was wrong: shrink the bracket).
    const double margin = !nudged                  ? std::min(0.1 * tolerance, 0.5 * width)
                          : width > 10 * tolerance ? 0.1 * width
                                                   : 0.5 * width;
    nudged = false;
    if (!(t - result.t_left >= 0.5 * tolerance)) t = result.t_left + margin, nudged = true;
    if (!(result.t_right - t >= 0.5 * tolerance)) t = result.t_right - margin, nudged = true;
    if (!(t > result.t_left && t < result.t_right)) t = result.t_left + 0.5 * width;
    if (!(t > result.t_left && t < result.t_right)) break;  // the interval is down to one ulp

    ++result.evaluations;
    if (!guards(t, middle)) {
      result.ok = false;
      return result;
    }
    previous_side = side;
    if (steering_guard(middle) >= 0) {
      result.t_right = t;
      high = middle;
      side = 1;
    } else {
      result.t_left = t;
      for (int k = 0; k < count; ++k) low[k] = on_old_side(middle[k], old_side[k]);
      side = 2;
    }
    steer = steering_guard(high);
  }
  return result;
}

}  // namespace padae
