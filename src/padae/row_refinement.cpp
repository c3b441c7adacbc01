#include "padae/row_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace padae {

namespace {

// Halvings of the step at most: a kink is left to the rows' solves once it is this narrowed.
constexpr int kMaxDepth = 6;

}  // namespace

// The ends' solutions are filled in when the step is first split: most steps never are.
void RowRefinement::reset(long step, double t_start, double t_end) {
  step_ = step;
  node_count_ = 0;
  add_node(t_start);
  add_node(t_end);
  intervals_.assign(1, Interval{0, 1, -1, 0, kUnchecked, kUnchecked});
}

int RowRefinement::add_node(double t) {
  if (static_cast<std::size_t>(node_count_) == nodes_.size()) nodes_.emplace_back();
  node(node_count_).t = t;
  return node_count_++;
}

std::size_t RowRefinement::interval_at(double t) const {
  if (intervals_.size() == 1) return 0;  // the step unsplit, as most are
  auto after = std::upper_bound(intervals_.begin(), intervals_.end(), t,
                                [this](double at, const Interval& interval) { return at < node(interval.start).t; });
  return after == intervals_.begin() ? 0 : static_cast<std::size_t>(after - intervals_.begin() - 1);
}

std::array<double, 3> RowRefinement::weights(const Interval& interval, double t) const {
  const std::array<double, 3> at{node(interval.start).t, node(interval.middle).t, node(interval.end).t};
  std::array<double, 3> weight;
  for (int j = 0; j < 3; ++j) {
    weight[j] = 1;
    for (int k = 0; k < 3; ++k)
      if (k != j) weight[j] *= (t - at[k]) / (at[j] - at[k]);
  }
  return weight;
}

int RowRefinement::check(const Interval& interval, const Vector& inverse_weight) {
  const double start = node(interval.start).t, end = node(interval.end).t;
  const double middle = start + (end - start) / 2;
  polynomial_(middle, polynomial_at_);
  if (interval.depth == 0) {
    by_solution_ = polynomial_at_;
  } else {
    const std::array<double, 3> weight = weights(interval, middle);
    const Node& first = node(interval.start);
    const Node& second = node(interval.middle);
    const Node& third = node(interval.end);
    by_solution_ = weight[0] * first.x + weight[1] * second.x + weight[2] * third.x;
    by_deviation_ = polynomial_at_ + weight[0] * (first.x - first.polynomial) +
                    weight[1] * (second.x - second.polynomial) + weight[2] * (third.x - third.polynomial);
  }
  std::optional<Vector> solved = solve_(middle, by_solution_);
  if (!solved) return kUnsolved;
  const int index = add_node(middle);
  Node& checked = node(index);
  checked.miss_by_solution = (*solved - by_solution_).cwiseAbs().cwiseProduct(inverse_weight);
  if (interval.depth > 0) checked.miss_by_deviation = (*solved - by_deviation_).cwiseAbs().cwiseProduct(inverse_weight);
  checked.x = std::move(*solved);
  checked.polynomial = polynomial_at_;
  return index;
}

const Vector& RowRefinement::miss(const Interval& interval, int checked) const {
  return interval.by_deviation ? node(checked).miss_by_deviation : node(checked).miss_by_solution;
}

double RowRefinement::worst(const Vector& miss, std::span<const int> unknowns) {
  double largest = 0;
  for (int i : unknowns) {
    if (std::isnan(miss[i])) return std::numeric_limits<double>::infinity();
    largest = std::max(largest, miss[i]);
  }
  return largest;
}

bool RowRefinement::certified(const Interval& interval, std::span<const int> unknowns) const {
  auto within = [&](int checked) { return checked >= 0 && worst(miss(interval, checked), unknowns) <= 1; };
  // The whole step's check is its own sibling.
  return within(interval.check) && (interval.sibling_check == interval.check || within(interval.sibling_check));
}

void RowRefinement::split(std::size_t index, std::span<const int> unknowns, const Vector& inverse_weight) {
  const Interval parent = intervals_[index];
  if (parent.depth == 0)
    for (int end : {parent.start, parent.end}) {
      polynomial_(node(end).t, node(end).polynomial);
      node(end).x = node(end).polynomial;
    }
  Interval left{parent.start, parent.check, parent.end, parent.depth + 1, kUnsolved, kUnsolved};
  Interval right{parent.check, parent.end, parent.start, parent.depth + 1, kUnsolved, kUnsolved};
  left.check = right.sibling_check = check(left, inverse_weight);
  right.check = left.sibling_check = check(right, inverse_weight);
  // The interpolant that predicts the pair's checks better.
  auto pair_worst = [&](bool by_deviation) {
    Interval pair = left;
    pair.by_deviation = by_deviation;
    double largest = 0;
    for (int checked : {left.check, right.check})
      if (checked >= 0) largest = std::max(largest, worst(miss(pair, checked), unknowns));
    return largest;
  };
  left.by_deviation = right.by_deviation = pair_worst(true) < pair_worst(false);
  if (parent.depth == 0) {
    ++first_splits_;
    if (certified(left, unknowns) && certified(right, unknowns)) ++first_splits_passed_;
  }
  intervals_[index] = left;
  intervals_.insert(intervals_.begin() + static_cast<std::ptrdiff_t>(index) + 1, right);
}

// Certifying an interval by splitting takes 2 + 4 + ... checks, one solve each, against one
// solve for each of its rows. Each halving divides a quadratic's error by about 8 (it is
// O(h^3)). The step's own polynomial is another interpolant, whose miss says nothing of the
// quadratics': the first split's two checks save the rows only if both pass, which they do about
// as often as they did so far in the run (a third of the time on a bridge rectifier's floating
// load, nine in ten on a boost converter's switch node), counted from a prior of one in three.
bool RowRefinement::splitting_costs_more(const Interval& interval, std::span<const int> unknowns) const {
  const double rows = (node(interval.end).t - node(interval.start).t) / row_spacing_;
  if (interval.depth == 0) {
    const double pass_rate = (first_splits_passed_ + 1.0) / (first_splits_ + 3.0);
    return 2 / pass_rate >= rows;
  }
  double largest = worst(miss(interval, interval.check), unknowns);
  if (!std::isfinite(largest)) return true;
  int halvings = 1;
  while (largest > 8 && halvings < kMaxDepth) largest /= 8, ++halvings;
  return std::ldexp(2.0, halvings) - 2 >= rows;
}

RowRefinement::Row RowRefinement::row(double t, std::span<const int> unknowns, const Vector& inverse_weight) {
  if (t > last_row_) row_spacing_ = t - last_row_;
  last_row_ = t;
  for (;;) {
    const std::size_t index = interval_at(t);
    if (intervals_[index].check == kUnchecked) {  // the whole step: S against its midpoint
      const int checked = check(intervals_[index], inverse_weight);
      intervals_[index].check = intervals_[index].sibling_check = checked;
    }
    const Interval& interval = intervals_[index];
    if (interval.check == kUnsolved) return Row::solved;
    if (certified(interval, unknowns)) return interval.depth == 0 ? Row::polynomial : Row::interpolated;
    if (interval.depth == kMaxDepth || splitting_costs_more(interval, unknowns)) return Row::solved;
    split(index, unknowns, inverse_weight);
  }
}

void RowRefinement::interpolate(double t, std::span<const int> unknowns, Vector& out) const {
  const Interval& interval = intervals_[interval_at(t)];
  const std::array<double, 3> weight = weights(interval, t);
  const Node& first = node(interval.start);
  const Node& second = node(interval.middle);
  const Node& third = node(interval.end);
  if (interval.by_deviation) {
    for (int i : unknowns)
      out[i] += weight[0] * (first.x[i] - first.polynomial[i]) + weight[1] * (second.x[i] - second.polynomial[i]) +
                weight[2] * (third.x[i] - third.polynomial[i]);
  } else {
    for (int i : unknowns) out[i] = weight[0] * first.x[i] + weight[1] * second.x[i] + weight[2] * third.x[i];
  }
}

}  // namespace padae
