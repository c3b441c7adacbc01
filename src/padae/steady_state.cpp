#include "padae/steady_state.hpp"

#include <cmath>
#include <limits>
#include <optional>

#include "padae/newton_matrix.hpp"
#include "padae/norms.hpp"
#include "padae/subnormals.hpp"

namespace padae {

namespace {

constexpr int kMaxNewtonIterations = 60;
constexpr double kConvergedNorm = 1e-3;  // Newton correction, in tolerance units

class SteadyStateSolver {
 public:
  SteadyStateSolver(System& system, double t, const Options& options)
      : system_(system),
        t_(t),
        options_(options),
        absolute_tolerance_(Vector::NullaryExpr(system.size(), [&](Eigen::Index i) {
          return system.absolute_tolerance(static_cast<int>(i), options.atol);
        })),
        newton_(system, statistics_, absolute_tolerance_) {}

  // Newton on f(t, x, p) = 0 (shift = 0), or on (x - x_previous) shift + f = 0.
  bool newton(Vector& x, const Vector& x_previous, const Predicates& p, double shift) {
    const Vector held = x;
    left_domain_at_.reset();
    left_domain_ = false;
    double previous_norm = std::numeric_limits<double>::infinity();
    for (int iteration = 0; iteration < kMaxNewtonIterations; ++iteration) {
      const NewtonMatrix::Outcome outcome = newton_.factor_shifted(t_, x, p, shift);
      if (outcome != NewtonMatrix::Outcome::ok) {
        left_domain_ = outcome == NewtonMatrix::Outcome::outside_domain;
        if (left_domain_ && iteration > 0) left_domain_at_ = x;
        worst_ = left_domain_ ? newton_.first_non_finite_row() : newton_.singular_column();
        return false;
      }
      Vector delta = newton_.load().f + shift * (x - x_previous);
      for (int i : newton_.auxiliary_unknowns()) delta[i] = x[i] - held[i];
      newton_.solve(delta);
      const double fraction = newton_.step_fraction(x, x - delta);
      x -= fraction * delta;
      double norm = 0;
      for (Eigen::Index i = 0; i < x.size(); ++i) {
        double scaled = std::abs(delta[i]) / (options_.rtol * std::abs(x[i]) + absolute_tolerance_[i]);
        if (!(scaled <= norm)) norm = scaled, worst_ = static_cast<int>(i);
      }
      if (!std::isfinite(norm)) return false;
      if (fraction == 1 && norm <= kConvergedNorm) return true;
      // Each iteration's matrix is fresh (boost.cir at reltol 1e-14 stalled so).
      if (fraction == 1 && stalled_at_roundoff(norm, previous_norm)) return true;
      previous_norm = fraction == 1 ? norm : std::numeric_limits<double>::infinity();
    }
    return false;
  }

  // Pseudo-transient continuation: implicit steps of a fictitious relaxation, longer and
  // longer, until the steady equations themselves converge.
  bool pseudo_transient(Vector& x, const Predicates& p) {
    double shift = 1e6;
    for (int attempt = 0; attempt < 200; ++attempt) {
      Vector trial = x;
      if (newton(trial, x, p, shift)) {
        x = trial;
        Vector final_attempt = x;
        if (newton(final_attempt, x, p, 0.0)) {
          x = final_attempt;
          return true;
        }
        shift *= 0.1;
      } else {
        shift *= 10;
        if (shift > 1e30) return false;
      }
    }
    return false;
  }

  // The predicate whose guard most contradicts mode p at x; -1 if none does (or the guards
  // cannot be evaluated there).
  int most_contradicted(const Vector& x, const Predicates& p) {
    Vector values;
    if (!guard_values(x, values)) return -1;
    int worst = -1;
    for (int k = 0; k < system_.predicate_count(); ++k)
      if ((values[k] > 0) != static_cast<bool>(p[k]) && (worst < 0 || std::abs(values[k]) > std::abs(values[worst])))
        worst = k;
    return worst;
  }

  // The same at the relaxed steady state from x, where mode p has none: which way the state
  // goes. The relaxation's shift is a conductance to ground at each node and a resistance in
  // series with each branch whose current is an unknown; the smallest that converges opens a
  // cut-set of current sources and breaks a loop of voltage sources, and leaves the rest to the
  // circuit's own elements.
  int most_contradicted_relaxed(const Vector& x, const Predicates& p) {
    for (double shift = 1e-9; shift <= 1e6; shift *= 1e3) {
      Vector relaxed = x;
      if (newton(relaxed, x, p, shift)) return most_contradicted(relaxed, p);
    }
    return -1;
  }

  bool guard_values(const Vector& x, Vector& values) {
    values.setZero(system_.predicate_count());
    return system_.guards(t_, x, values) == EvalStatus::ok;
  }

  bool guards(const Vector& x, Predicates& p) {
    Vector values;
    if (!guard_values(x, values)) return false;
    for (int k = 0; k < system_.predicate_count(); ++k) p[k] = values[k] > 0;
    return true;
  }

  void jump(Vector& x, const Predicates& from, const Predicates& to) {
    if (!system_.has_jumps()) return;
    std::vector<JumpEntry> entries;
    system_.jump_matrix(t_, x, from, entries);
    for (const JumpEntry& entry : entries)
      if (from[entry.predicate] != to[entry.predicate])
        x[entry.row] += entry.value * (to[entry.predicate] ? 1.0 : -1.0);
  }

  int worst() const { return worst_; }
  // Whether the last newton() failed because the model could not be evaluated.
  bool left_domain() const { return left_domain_; }
  // The iterate at which the last newton() left the model's domain, if it did.
  const std::optional<Vector>& left_domain_at() const { return left_domain_at_; }

 private:
  System& system_;
  double t_;
  const Options& options_;
  Statistics statistics_;
  Vector absolute_tolerance_;
  NewtonMatrix newton_;
  int worst_ = -1;
  bool left_domain_ = false;
  std::optional<Vector> left_domain_at_;
};

}  // namespace

SteadyState steady_state(System& system, double t, const Vector& x_guess, const Predicates& p0,
                         const Options& options) {
  SubnormalsFlushed flushed;
  SteadyState result;
  SteadyStateSolver solver(system, t, options);
  result.x = x_guess;
  result.p = p0;
  if (result.p.empty() && system.predicate_count() > 0) {
    result.p.assign(static_cast<std::size_t>(system.predicate_count()), 0);
    if (!solver.guards(result.x, result.p)) {
      result.message = "a guard function cannot be evaluated at the initial guess";
      return result;
    }
  }
  // Iterate the modes to a fixed point: solve with p, re-evaluate the predicates, flip every one
  // that disagrees, repeat. Where a mode so reached has no steady state (ideal diodes in a
  // bridge: all off, a current source has no path; all on, they short the source), the search
  // goes back to the last mode solved and from then on flips one predicate at a time, the one
  // its guard contradicts most, as a complementarity problem is pivoted.
  struct SolvedMode {
    Vector x;
    Predicates p;
  };
  std::optional<SolvedMode> solved;
  bool one_at_a_time = false;
  auto flip = [&](const Predicates& next) {
    solver.jump(result.x, result.p, next);
    result.p = next;
  };
  auto flip_one = [&](int k) {
    Predicates next = result.p;
    next[k] = !next[k];
    flip(next);
  };
  for (int iteration = 0; iteration < options.max_event_iterations; ++iteration) {
    Vector x = result.x;
    if (!solver.newton(x, x, result.p, 0.0)) {
      // Newton left the model's domain: a mode's branch taken past its guard (abs(v) = -v where
      // v > 0, under a sqrt). The guards where it left choose the modes to go on in.
      if (const auto& left = solver.left_domain_at(); left && system.predicate_count() > 0) {
        Predicates there = result.p;
        if (solver.guards(*left, there) && there != result.p) {
          result.x = *left;
          flip(there);
          continue;
        }
      }
      x = result.x;
      if (!solver.pseudo_transient(x, result.p)) {
        if (solved && !one_at_a_time) {
          one_at_a_time = true;
          result.x = solved->x;
          result.p = solved->p;
          if (const int k = solver.most_contradicted(result.x, result.p); k >= 0) {
            flip_one(k);
            continue;
          }
        }
        if (const int k = solver.most_contradicted_relaxed(result.x, result.p); k >= 0) {
          one_at_a_time = true;
          flip_one(k);
          continue;
        }
        result.message = solver.left_domain()
                             ? "no steady state: the model cannot be evaluated (outside its domain) where Newton's "
                               "method and pseudo-transient continuation go"
                             : "no steady state: Newton's method and pseudo-transient continuation fail";
        result.worst_unknown = solver.worst();
        return result;
      }
    }
    result.x = x;
    if (system.predicate_count() == 0) {
      result.converged = true;
      return result;
    }
    Predicates next = result.p;
    if (!solver.guards(result.x, next)) {
      result.message = "a guard function cannot be evaluated at the steady state";
      return result;
    }
    if (next == result.p) {
      result.converged = true;
      return result;
    }
    solved = SolvedMode{result.x, result.p};
    const int k = one_at_a_time ? solver.most_contradicted(result.x, result.p) : -1;
    if (k >= 0) flip_one(k);
    else flip(next);
  }
  result.message =
      "the predicates do not settle at a steady state (they keep flipping: an oscillator has none; start it from "
      "initial conditions)";
  return result;
}

}  // namespace padae
