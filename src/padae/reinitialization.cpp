#include "padae/reinitialization.hpp"

#include <cmath>
#include <limits>

#include "padae/damped_newton.hpp"
#include "padae/norms.hpp"

namespace padae {

namespace {

constexpr int kMaxIterations = 100;          // junctions far from their solution need many
constexpr double kConvergedNorm = 1e-3;     // Newton correction, in tolerance units
constexpr double kRefactorRate = 0.1;       // refactor when Newton contracts slower than this
constexpr double kRefinementStalled = 0.9;  // on an exact matrix, a slower contraction stops
constexpr double kEps = std::numeric_limits<double>::epsilon();
// The settling steps' length, relative to the integrator's step: short enough that the
// extrapolation's O(h^2) error is far below a step's local error, long enough that the steps'
// conditioning is within 1e3 of the integrator's own.
constexpr double kSettleFraction = 1e-3;
constexpr double kSettleAccuracy = 1e-2;  // extrapolation error, in units of the error tolerance
constexpr double kChargesKept = 1;        // charges moved by a settled fast mode, in the same units

}  // namespace

Reinitializer::Reinitializer(System& system, NewtonMatrix& newton, Statistics& statistics,
                             const Options& options, const Vector& absolute_tolerance,
                             const Vector& peak_magnitude)
    : system_(system),
      newton_(newton),
      statistics_(statistics),
      options_(options),
      absolute_tolerance_(absolute_tolerance),
      peak_magnitude_(peak_magnitude) {}

// The tolerance never asks for less than round-off in x.
void Reinitializer::newton_weights(const Vector& x, Vector& inverse_weight) const {
  inverse_weight = ((options_.rtol + 100 * kEps) * x.cwiseAbs() + absolute_tolerance_).cwiseInverse();
}

bool Reinitializer::backward_euler(double t_eval, double h, const Vector& q_start,
                                   const Vector& held, const Predicates& p_from,
                                   const Predicates& p_to, double lambda, Vector& x) {
  const double cj = 1 / h;
  const bool blended = lambda < 1;
  auto factor = [&]() {
    return blended ? newton_.factor_blend(t_eval, x, p_from, p_to, lambda, cj)
                   : newton_.factor(t_eval, x, p_to, cj);
  };
  auto evaluate = [&]() {
    if (!blended) return newton_.evaluate(t_eval, x, p_to) == EvalStatus::ok;
    return newton_.factor_blend(t_eval, x, p_from, p_to, lambda, cj) == NewtonMatrix::Outcome::ok;
  };

  double previous_norm = std::numeric_limits<double>::infinity();
  bool refactor = true;
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    if (refactor) {
      auto outcome = factor();
      if (outcome != NewtonMatrix::Outcome::ok) {
        if (outcome == NewtonMatrix::Outcome::outside_domain) {
          outside_domain_at(t_eval, x, {&p_to, &p_from}, "the model cannot be evaluated in the new mode");
          return false;
        }
        failure_reason_ = "the circuit equations are singular in the new mode";
        failure_unknown_ = newton_.singular_column();
        if (lambda == 1) singular_state_ = x;
        return false;
      }
    } else if (!evaluate()) {
      outside_domain_at(t_eval, x, {&p_to, &p_from}, "the model cannot be evaluated in the new mode");
      return false;
    }
    ++statistics_.newton_iterations;
    const Load& load = newton_.load();
    Vector& delta = delta_;
    delta = (load.q - q_start) * cj + load.f;
    for (int i : newton_.auxiliary_unknowns()) delta[i] = x[i] - held[i];
    newton_.solve(delta);
    // A step the model limits (a junction sent from reverse bias far into conduction) is taken
    // in part, and shows the matrix's linearization was far off: refactored at the next iterate.
    const double fraction = newton_.step_fraction(x, x - delta);
    x -= fraction * delta;
    Vector& inverse_weight = inverse_weight_;
    newton_weights(x, inverse_weight);
    int worst = -1;
    const double norm = weighted_max_norm(delta, inverse_weight, &worst);
    if (!std::isfinite(norm)) {
      failure_reason_ = "Newton's method diverges in the new mode";
      failure_unknown_ = worst;
      return false;
    }
    double rate = norm / previous_norm;
    if (fraction == 1) {
      if (norm <= kConvergedNorm) return true;
      const bool exact_matrix = !blended && newton_.factored_exactly(p_to, cj);
      // Stalled within the tolerance (floating capacitors), or beyond it within the rounding of
      // the residual's terms: a source's current through a loop of capacitors (index 2) moves
      // by C/h per ulp of their voltages, more than its tolerance in steps this short.
      // An exact matrix is as fresh as a refactored one.
      if ((refactor || exact_matrix) && stalled(norm, previous_norm) &&
          (norm <= 1 || newton_.within_roundoff(delta, 1, inverse_weight, 1, x, cj * q_start)))
        return true;
      // On the exact matrix of affine equations the corrections after the first only refine
      // against the factorization's rounding, each by about its condition number times eps:
      // where that is no contraction none follows, and a longer step is better conditioned
      // (C / h of a 1e-20 s step against an open switch's 1e-12 S: sc_integrator.cir iterated
      // to overflow, charge_pump.cir for 100 iterations, at each event).
      if (exact_matrix && rate > kRefinementStalled) {
        failure_reason_ = "Newton's method stalls in the new mode (its matrix is too ill-conditioned)";
        failure_unknown_ = worst;
        return false;
      }
    }
    refactor = fraction < 1 || rate > kRefactorRate;
    // After a partial step the iteration starts afresh.
    previous_norm = fraction < 1 ? std::numeric_limits<double>::infinity() : norm;
    failure_unknown_ = worst;
  }
  failure_reason_ = "Newton's method does not converge in the new mode";
  return false;
}

bool Reinitializer::damped_backward_euler(double t_eval, double h, const Vector& q_start,
                                          const Vector& held, const Predicates& p, Vector& x) {
  const Vector no_derivative = Vector::Zero(x.size());
  const CorrectorEquation equation{t_eval, 1 / h, q_start, no_derivative, held, p};
  newton_weights(x, inverse_weight_);
  return solve_damped(newton_, statistics_, equation, inverse_weight_, kConvergedNorm, options_.rtol, kMaxIterations,
                      x) == NewtonOutcome::converged;
}

bool Reinitializer::backward_euler_with_continuation(double t_eval, double h,
                                                     const Vector& q_start,
                                                     const Predicates& p_from,
                                                     const Predicates& p_to, Vector& x) {
  const Vector guess = x;
  if (backward_euler(t_eval, h, q_start, guess, p_from, p_to, 1.0, x)) return true;
  // The plain iteration can cycle where a junction's limiting and its turn-off alternate (a
  // flyback's secondary diode, reverse-saturated, as the switch turns on: v(sec) between
  // -0.2 V and 9.8 V, 100 iterations); damped Newton's monotonicity test breaks the cycle.
  // Its failure leaves the plain iteration's reason standing.
  const std::string plain_failure = failure_reason_;
  const int plain_unknown = failure_unknown_;
  x = guess;
  if (damped_backward_euler(t_eval, h, q_start, guess, p_to, x)) return true;
  failure_reason_ = plain_failure;
  failure_unknown_ = plain_unknown;
  if (p_from == p_to) return false;
  // Continuation in a parameter (the paper's remedy): from the old mode, whose solution is
  // near x, to the new one.
  x = guess;
  if (!backward_euler(t_eval, h, q_start, guess, p_from, p_to, 0.0, x)) return false;
  double lambda = 0, increment = 0.25;
  while (lambda < 1) {
    double next = std::min(1.0, lambda + increment);
    Vector trial = x;
    if (backward_euler(t_eval, h, q_start, guess, p_from, p_to, next, trial)) {
      x = trial;
      lambda = next;
      increment = std::min(2 * increment, 1.0);
    } else if ((increment *= 0.5) < 1e-6) {
      failure_reason_ = "no consistent state in the new mode (continuation stalled at " +
                        std::to_string(lambda) + ")";
      stalled_state_ = x;
      return false;
    }
  }
  return true;
}

std::optional<ConsistentState> Reinitializer::jump(double t, const Vector& x_start,
                                                   const Predicates& p_from,
                                                   const Predicates& p_to, double h_reference) {
  stalled_state_.reset();
  singular_state_.reset();
  failure_unknown_ = -1;
  if (newton_.evaluate(t, x_start, p_from) != EvalStatus::ok) {
    outside_domain_at(t, x_start, {&p_from}, "the model cannot be evaluated at the event");
    outside_domain_state_.reset();  // the state before the event: it names no other mode
    return std::nullopt;
  }
  const Vector q_before = newton_.load().q;
  outside_domain_state_.reset();
  // The impulse step is as short as the time resolution allows. Where Newton fails on it
  // (a capacitor without a DC path of its own: C/h swamps every conductance in double
  // precision, the matrix is singular or the iteration stalls at round-off) it is lengthened up
  // to the settling step: its charges stay exact either way, since LU is backward stable, and
  // the settling steps fix the algebraic directions.
  const double h_settle = settle_step(t, h_reference);
  const double h_vanishing = time_resolution(t, options_);
  Vector x_plus;
  double h_impulse = 0;
  // Lengthening is cheap and cures conditioning; continuation in the modes cures a nonlinear
  // start (a junction far from its new operating point): lengths first, then continuation.
  // Its sources are evaluated at t + h_vanishing, whatever its length: on the right side of a
  // source that jumps at t, and no further. Lengthened and evaluated at its end, it took a
  // ramping source along, and the charges with it: a clock falling at 1 V/ns moved a 1 pF node's
  // charge by 440 times its tolerance in a step of 3e-15 s (rtol 1e-7), which the integration
  // then had to undo in no time (a 4-stage charge pump stopped at its first falling edge).
  for (bool continuation : {false, true}) {
    for (h_impulse = h_vanishing;; h_impulse = std::min(1e3 * h_impulse, h_settle)) {
      x_plus = x_start;
      bool solved = continuation
                        ? backward_euler_with_continuation(t + h_vanishing, h_impulse, q_before, p_from, p_to, x_plus)
                        : backward_euler(t + h_vanishing, h_impulse, q_before, x_start, p_from, p_to, 1.0, x_plus);
      if (solved) break;
      if (h_impulse >= h_settle) {
        h_impulse = 0;
        break;
      }
    }
    if (h_impulse > 0 || p_from == p_to) break;
  }
  if (h_impulse == 0) return std::nullopt;
  if (newton_.evaluate(t, x_plus, p_to) != EvalStatus::ok) {
    outside_domain_at(t, x_plus, {&p_to}, "the model cannot be evaluated after the event");
    return std::nullopt;
  }
  const Vector q_plus = newton_.load().q;
  auto consistent = settle(t, x_plus, q_plus, p_to, h_settle);
  if (!consistent) return consistent;
  consistent->impulse = h_impulse * x_plus;
  // A jump moves q by far more than the smooth motion does over the impulse step, and than the
  // rounding of the charges it sums (of their size |dq/dx| |x|: q itself may be measured from
  // any reference).
  Vector charge_size;
  newton_.charge_scale(x_start.cwiseAbs().cwiseMax(x_plus.cwiseAbs()), charge_size);
  for (Eigen::Index i = 0; i < q_before.size(); ++i) {
    double moved = std::abs(q_plus[i] - q_before[i]);
    double smooth = 10 * h_impulse * std::abs(consistent->q_derivative[i]);
    if (moved > smooth + 1e-10 * charge_size[i] + std::numeric_limits<double>::min()) consistent->charges_moved = true;
  }
  return consistent;
}

// The settling steps (up to 4h) stay short of the next source corner: past it the motion is
// not the one that starts at t. Corners within the time resolution of t are at t (two clocks'
// edges at 8 us computed two ways differ by an ulp), and the vanishing step took the sources
// past them.
double Reinitializer::settle_step(double t, double h_reference) const {
  const double resolution = time_resolution(t, options_);
  const double h = std::max(kSettleFraction * h_reference, 1e5 * resolution);
  return std::min(h, (system_.next_time_event(t + resolution) - t) / 8);
}

// Backward-Euler steps from the charges after the jump, of lengths h, 2h and 4h, and their
// polynomial extrapolation to h = 0: the state at t + 0 with the algebraic unknowns (and the
// hidden algebraic directions of floating capacitors) consistent, accurate to O(h^3), while the
// steps stay well conditioned. A mode faster than the steps (a switch's RC of a nanosecond
// against microsecond steps) is not polynomial over them: the difference between the quadratic
// and the linear extrapolation shows it, and h is shortened until it is resolved. A mode so fast
// that all three steps see it settled (a picosecond RC against steps of 10 us) shows instead as
// extrapolated charges off the ones the steps start from; where even the shortest steps settle
// it, the state at t + 0 is the vanishing step's (its charges are exact: nothing but the fast
// mode's own motion moves them).
std::optional<ConsistentState> Reinitializer::settle(double t, const Vector& x_plus,
                                                     const Vector& q_plus, const Predicates& p,
                                                     double h) {
  const double h_shortest = 1e3 * time_resolution(t, options_);
  const Vector inverse_weight =
      (options_.rtol * x_plus.cwiseAbs() + absolute_tolerance_).cwiseInverse();
  Vector differential_weight = inverse_weight;
  for (int i = 0; i < system_.size(); ++i)
    if (system_.kind(i) != UnknownKind::differential) differential_weight[i] = 0;
  // The charges are kept within the error test's own tolerance (relative to each unknown's
  // peak so far, where Options::peak_floor asks for it): a fast mode that moves them by less than
  // a step's error may settle (an ideal diode's ROFF draining its inductor's last 40 pA in
  // 1e-17 s; ROFF = 1e9 against 2 mH moving 4e-7 A of 15 A in 2 ps).
  Vector charge_tolerance;
  newton_.charge_scale(options_.rtol * error_scale(x_plus, peak_magnitude_, options_.peak_floor) + absolute_tolerance_,
                       charge_tolerance);
  const Vector inverse_charge_weight =
      charge_tolerance.unaryExpr([](double w) { return w > 0 ? 1 / w : 0.0; });
  // Whether the extrapolation reproduces the charges the steps start from.
  auto keeps_charges = [&](const Vector& x_at) {
    return newton_.evaluate(t, x_at, p) == EvalStatus::ok &&
           weighted_max_norm(newton_.load().q - q_plus, inverse_charge_weight) <= kChargesKept;
  };
  Vector x_one, x_two, x_four, extrapolated;
  // Shorter steps also where Newton fails: the motion over a long step may be far from x_plus.
  // Where the shorter steps fail (round-off of an ill-conditioned matrix), the last
  // extrapolation stands.
  bool have_extrapolation = false, charges_kept = false;
  for (;; h *= 1e-3) {
    Vector one = x_plus;
    bool solved = backward_euler_with_continuation(t + h, h, q_plus, p, p, one);
    Vector two = one;
    solved = solved && backward_euler_with_continuation(t + 2 * h, 2 * h, q_plus, p, p, two);
    Vector four = two;
    solved = solved && backward_euler_with_continuation(t + 4 * h, 4 * h, q_plus, p, p, four);
    if (!solved && have_extrapolation) {
      h *= 1e3;
      break;
    }
    if (!solved) {
      if (h * 1e-3 < h_shortest) return std::nullopt;
      continue;
    }
    x_one = std::move(one), x_two = std::move(two), x_four = std::move(four);
    // Lagrange weights of the nodes h, 2h, 4h at 0; the linear extrapolation is 2 x1 - x2.
    extrapolated = (8 * x_one - 6 * x_two + x_four) / 3;
    have_extrapolation = true;
    const Vector curvature = (2 * x_one - 3 * x_two + x_four) / 3;
    // Curvature that the rounding of the three solutions explains is noise, which shorter steps
    // only amplify. Their rounding, estimated on the last factorization (the 4h step's), is at
    // most 4 and 2 times as large for the h and 2h steps (C/h per ulp), so at most 5 times in
    // the curvature.
    const bool resolved = weighted_max_norm(curvature, inverse_weight) <= kSettleAccuracy ||
                          newton_.within_roundoff(curvature, kSettleAccuracy, inverse_weight, 5, x_four, q_plus / (4 * h));
    charges_kept = keeps_charges(extrapolated);
    if ((resolved && charges_kept) || h * 1e-3 < h_shortest) break;
  }
  ConsistentState state;
  state.x_impulse = x_plus;
  state.x = charges_kept ? extrapolated : x_plus;
  state.fast_mode_left = !charges_kept;
  if (!derivatives_at(t, p, state)) return std::nullopt;
  // The vanishing step's differential unknowns are exact where it was well conditioned, and
  // the extrapolation agrees with them to Newton's tolerance; where they differ by more than a
  // tenth of the error tolerance the vanishing step lost the hidden algebraic directions. The
  // state takes their charges, but keeps q' from the extrapolation, whose algebraic unknowns
  // were solved with its own differential ones: across a small resistance (a diode's RS of
  // 10 mOhm) the difference between the two is a current that -f would pass into q' as charge
  // created on a cut-set (22 uA where three source inductors close it: a three-phase bridge
  // stopped at t = 0).
  if (charges_kept && weighted_max_norm(x_plus - extrapolated, differential_weight) <= 0.1) {
    for (int i = 0; i < system_.size(); ++i)
      if (system_.kind(i) == UnknownKind::differential) state.x[i] = x_plus[i];
    if (newton_.evaluate(t, state.x, p) != EvalStatus::ok) {
      outside_domain_at(t, state.x, {&p}, "the model cannot be evaluated after the event");
      return std::nullopt;
    }
    state.q = newton_.load().q;
  }
  state.x_derivative = (x_one - state.x) / h;
  state.t_heading = t + h;
  state.x_heading = x_one;
  // The first settling step's -f is q' at t + h: a fast mode the new motion starts shows as
  // curvature, which bounds the first step after the restart.
  if (newton_.evaluate(t + h, x_one, p) != EvalStatus::ok) {
    outside_domain_at(t + h, x_one, {&p}, "the model cannot be evaluated after the event");
    return std::nullopt;
  }
  state.q_second_derivative = (-newton_.load().f - state.q_derivative) / h;
  newton_.keep_dynamic_rows(state.q_second_derivative);
  return state;
}

void Reinitializer::outside_domain_at(double t, const Vector& x, std::initializer_list<const Predicates*> modes,
                                      const char* reason) {
  failure_reason_ = reason;
  outside_domain_state_ = x;
  // The first equation a mode cannot evaluate at x names its element.
  for (const Predicates* p : modes) {
    if (newton_.evaluate(t, x, *p) == EvalStatus::ok) continue;
    if (const int row = newton_.first_non_finite_row(); row >= 0) {
      failure_unknown_ = row;
      return;
    }
  }
}

// q and its right derivative -f (dynamic rows) at the consistent state.x.
bool Reinitializer::derivatives_at(double t, const Predicates& p, ConsistentState& state) {
  if (newton_.evaluate(t, state.x, p) != EvalStatus::ok) {
    outside_domain_at(t, state.x, {&p}, "the model cannot be evaluated after the event");
    return false;
  }
  state.q = newton_.load().q;
  state.q_derivative = -newton_.load().f;
  newton_.keep_dynamic_rows(state.q_derivative);
  return true;
}

}  // namespace padae
