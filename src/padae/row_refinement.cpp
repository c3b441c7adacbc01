#include "padae/row_refinement.hpp"

#include <algorithm>

namespace padae {

namespace {

// Halvings of the step at most: a kink is left to the rows' solves once it is this narrowed.
constexpr int kMaxDepth = 6;

}  // namespace

void RowRefinement::reset(long step, double t_start, double t_end, const Polynomial& polynomial) {
  step_ = step;
  node_count_ = 0;
  for (double t : {t_start, t_end}) {
    Node& end = node(add_node(t));
    polynomial(t, end.polynomial);
    end.x = end.polynomial;
  }
  intervals_.assign(1, Interval{0, 1, -1, 0, kUnchecked, kUnchecked});
}

int RowRefinement::add_node(double t) {
  if (static_cast<std::size_t>(node_count_) == nodes_.size()) nodes_.emplace_back();
  node(node_count_).t = t;
  return node_count_++;
}

std::size_t RowRefinement::interval_at(double t) const {
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

int RowRefinement::check(const Interval& interval, const Vector& inverse_weight, const Polynomial& polynomial,
                         const Solve& solve) {
  const double start = node(interval.start).t, end = node(interval.end).t;
  const double middle = start + (end - start) / 2;
  polynomial(middle, polynomial_);
  if (interval.depth == 0) {
    by_solution_ = polynomial_;
  } else {
    const std::array<double, 3> weight = weights(interval, middle);
    const Node& first = node(interval.start);
    const Node& second = node(interval.middle);
    const Node& third = node(interval.end);
    by_solution_ = weight[0] * first.x + weight[1] * second.x + weight[2] * third.x;
    by_deviation_ = polynomial_ + weight[0] * (first.x - first.polynomial) +
                    weight[1] * (second.x - second.polynomial) + weight[2] * (third.x - third.polynomial);
  }
  std::optional<Vector> solved = solve(middle, by_solution_);
  if (!solved) return kUnsolved;
  const int index = add_node(middle);
  Node& checked = node(index);
  checked.miss_by_solution = (*solved - by_solution_).cwiseAbs().cwiseProduct(inverse_weight);
  if (interval.depth > 0) checked.miss_by_deviation = (*solved - by_deviation_).cwiseAbs().cwiseProduct(inverse_weight);
  checked.x = std::move(*solved);
  checked.polynomial = polynomial_;
  return index;
}

bool RowRefinement::certified(const Interval& interval, std::span<const int> unknowns) const {
  for (int checked : {interval.check, interval.sibling_check}) {
    if (checked < 0) return false;
    const Vector& miss = interval.by_deviation ? node(checked).miss_by_deviation : node(checked).miss_by_solution;
    for (int i : unknowns)
      if (!(miss[i] <= 1)) return false;
  }
  return true;
}

void RowRefinement::split(std::size_t index, std::span<const int> unknowns, const Vector& inverse_weight,
                          const Polynomial& polynomial, const Solve& solve) {
  const Interval parent = intervals_[index];
  Interval left{parent.start, parent.check, parent.end, parent.depth + 1, kUnsolved, kUnsolved};
  Interval right{parent.check, parent.end, parent.start, parent.depth + 1, kUnsolved, kUnsolved};
  left.check = right.sibling_check = check(left, inverse_weight, polynomial, solve);
  right.check = left.sibling_check = check(right, inverse_weight, polynomial, solve);
  // The interpolant that predicts the pair's checks better.
  auto worst = [&](bool by_deviation) {
    double largest = 0;
    for (int checked : {left.check, right.check}) {
      if (checked < 0) continue;
      const Vector& miss = by_deviation ? node(checked).miss_by_deviation : node(checked).miss_by_solution;
      for (int i : unknowns) largest = std::max(largest, miss[i]);
    }
    return largest;
  };
  left.by_deviation = right.by_deviation = worst(true) < worst(false);
  intervals_[index] = left;
  intervals_.insert(intervals_.begin() + static_cast<std::ptrdiff_t>(index) + 1, right);
}

RowRefinement::Row RowRefinement::row(double t, std::span<const int> unknowns, const Vector& inverse_weight,
                                      const Polynomial& polynomial, const Solve& solve) {
  if (t > last_row_) row_spacing_ = t - last_row_;
  last_row_ = t;
  for (;;) {
    const std::size_t index = interval_at(t);
    if (intervals_[index].check == kUnchecked) {  // the whole step: S against its midpoint
      const int checked = check(intervals_[index], inverse_weight, polynomial, solve);
      intervals_[index].check = intervals_[index].sibling_check = checked;
    }
    const Interval& interval = intervals_[index];
    if (interval.check == kUnsolved) return Row::solved;
    if (certified(interval, unknowns)) return interval.depth == 0 ? Row::polynomial : Row::interpolated;
    // Halves checked by a solve each save solves only where each holds more than one row.
    const double half = (node(interval.end).t - node(interval.start).t) / 2;
    if (interval.depth == kMaxDepth || half < 2 * row_spacing_) return Row::solved;
    split(index, unknowns, inverse_weight, polynomial, solve);
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
