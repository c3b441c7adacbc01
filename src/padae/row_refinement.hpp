// Output rows inside a step where its interpolating polynomial is not good enough: the solution,
// interpolated between points where it is solved, certified interval by interval.
//
// The step's polynomial S is error-controlled only for the charges. The other unknowns' solution
// inside the step (dense_output.hpp) can be far off it, and solving it at every row costs a
// Newton solve per row. S serves the step when it predicts the solution at the step's midpoint
// within the tolerance. Otherwise the step is split at its midpoint, and both halves are
// interpolated through the solution at the step's ends and midpoint; they serve when that
// predicts the solution at both halves' own midpoints. Both checks are needed: near a kink a
// quadratic through points on either side of it can pass through one check by coincidence. A
// half that does not serve is split in turn, its halves interpolated through its ends and
// midpoint. Two interpolants through those three points are tried, and the one that predicts
// the checks better is kept:
//  - the quadratic through the solution: where S is off because its history is (S of order k
//    passes through the last k steps' points; after a junction turned off, a bridge
//    rectifier's floating load, S bulges by volts while the solution stays flat);
//  - S plus the quadratic through the solution's deviation from S: where S has the solution's
//    shape but misses by a few tolerances (a junction's current while it conducts).
// An interval's interpolant is fixed when the interval is made, so a split elsewhere never
// changes a certified interval. Splitting stops where the checks it would take outnumber the
// rows they would spare (splitting_costs_more), or after kMaxDepth halvings; the rows of an
// interval that does not serve are solved (a kink: a junction turning on inside the step).
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "padae/system.hpp"

namespace padae {

class RowRefinement {
 public:
  // The solution at t inside the current step, Newton starting from guess; empty where Newton
  // fails.
  using Solve = std::function<std::optional<Vector>(double t, const Vector& guess)>;
  // The current step's polynomial S at t, into out.
  using Polynomial = std::function<void(double t, Vector& out)>;

  RowRefinement(Polynomial polynomial, Solve solve) : polynomial_(std::move(polynomial)), solve_(std::move(solve)) {}

  // Starts step number `step` from t_start to t_end (where S is the solution).
  void reset(long step, double t_start, double t_end);
  // Forgets the step (the integration restarted).
  void forget() { step_ = -1; }
  long step() const { return step_; }

  enum class Row {
    polynomial,    // S serves
    interpolated,  // interpolate() serves
    solved,        // no interpolant serves: the row is to be solved
  };
  // Where a row at t comes from for the listed unknowns, within 1 / inverse_weight; checks and
  // splits the interval holding t as needed.
  Row row(double t, std::span<const int> unknowns, const Vector& inverse_weight);
  // The interpolated solution at t (where row() says so) into out's listed unknowns, which hold
  // S(t) on entry.
  void interpolate(double t, std::span<const int> unknowns, Vector& out) const;

 private:
  // A point where the solution is known: the step's ends and the checked midpoints. At a check,
  // |x - prediction| * inverse_weight for the prediction of each interpolant.
  struct Node {
    double t = 0;
    Vector x;
    Vector polynomial;  // S(t)
    Vector miss_by_solution, miss_by_deviation;
  };
  static constexpr int kUnsolved = -1, kUnchecked = -2;
  struct Interval {
    int start, end;            // nodes
    int middle;                // its parent's midpoint: the third node of its quadratics
    int depth;                 // 0: the whole step, whose interpolant is S
    int check;                 // the node of its midpoint's check, or kUnsolved, kUnchecked
    int sibling_check;         // its sibling's, which certifies the same quadratic
    bool by_deviation = false; // the interpolant is S plus the quadratic of the deviation
  };

  // The solution at the interval's midpoint and its misses, in a new node; kUnsolved where
  // Newton fails.
  int check(const Interval& interval, const Vector& inverse_weight);
  // The misses of the interval's interpolant at a check node.
  const Vector& miss(const Interval& interval, int checked) const;
  // The largest of the listed unknowns' misses; infinite where one is NaN.
  static double worst(const Vector& miss, std::span<const int> unknowns);
  // Whether the interval's checks certify its interpolant for the unknowns.
  bool certified(const Interval& interval, std::span<const int> unknowns) const;
  // Whether certifying the interval by splitting it would take more solves than its rows.
  bool splitting_costs_more(const Interval& interval, std::span<const int> unknowns) const;
  // Replaces the interval at index by its two halves, checked.
  void split(std::size_t index, std::span<const int> unknowns, const Vector& inverse_weight);
  std::size_t interval_at(double t) const;
  // The Lagrange weights at t of the interval's quadratics (nodes start, middle, end).
  std::array<double, 3> weights(const Interval& interval, double t) const;
  int add_node(double t);
  Node& node(int index) { return nodes_[static_cast<std::size_t>(index)]; }
  const Node& node(int index) const { return nodes_[static_cast<std::size_t>(index)]; }

  Polynomial polynomial_;
  Solve solve_;
  long step_ = -1;
  std::vector<Node> nodes_;  // reused from step to step: entries beyond node_count_ are spare
  int node_count_ = 0;
  std::vector<Interval> intervals_;  // in time order, covering the step
  double last_row_ = 0, row_spacing_ = 0;
  long first_splits_ = 0, first_splits_passed_ = 0;  // whole steps split, and whose halves both served
  Vector polynomial_at_, by_solution_, by_deviation_;  // check()'s scratch
};

}  // namespace padae
