#include "padae/dense_output.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "padae/damped_newton.hpp"
#include "padae/norms.hpp"

namespace padae {

namespace {

constexpr int kMaxIterations = 100;      // junctions far from their solution need many
constexpr double kConvergedNorm = 1e-2;  // the corrections still to come, in tolerance units
constexpr double kFastContraction = 0.5;  // modified Newton goes on while it contracts this fast
// The factorization held serves the next row while its drift from the matrix at Newton's
// start (NewtonMatrix::drift) is within this: modified Newton then contracts about as fast as
// on a fresh matrix, so a small first correction is as telling. A matrix from another
// operating point can be far stiffer (a diode that has since turned off): a small correction
// on it proves nothing.
constexpr double kKeptMatrixDrift = 0.1;
constexpr double kEps = std::numeric_limits<double>::epsilon();
// Equally spaced rows extrapolate with |weights| summing to 7 through three points.
constexpr double kMaxAmplification = 8;

}  // namespace

DenseOutput::DenseOutput(System& system, Statistics& statistics, const Options& options,
                         const Vector& absolute_tolerance)
    : statistics_(statistics),
      newton_(system, statistics, absolute_tolerance / options.rtol),
      options_(options),
      absolute_tolerance_(absolute_tolerance) {}

std::optional<Vector> DenseOutput::solve(long step, double t, const Vector* x_guess, const Vector& x_polynomial,
                                         const Vector& q_polynomial, const Vector& q_derivative,
                                         const Predicates& p, double c) {
  if (!(c > 0) || !std::isfinite(c)) return std::nullopt;
  if (last_.step != step) last_.count = 0;
  const Vector* start = x_guess ? x_guess : &x_polynomial;
  if (!x_guess && last_.count > 0) {
    // Lagrange extrapolation through the newest of the last solutions' distances from S, as
    // many as it does not amplify their Newton error by more than kMaxAmplification (points
    // close together, far from t: a root finder's last brackets).
    std::array<double, kExtrapolationPoints> weights{};
    int count = last_.count;
    for (;; --count) {  // one point: weight 1
      double amplification = 0;
      for (int j = 0; j < count; ++j) {
        weights[j] = 1;
        for (int k = 0; k < count; ++k)
          if (k != j) weights[j] *= (t - last_.t[k]) / (last_.t[j] - last_.t[k]);
        amplification += std::abs(weights[j]);
      }
      if (amplification <= kMaxAmplification) break;
    }
    shifted_start_ = x_polynomial;
    for (int j = 0; j < count; ++j) shifted_start_ += weights[j] * last_.deviation[j];
    start = &shifted_start_;
  }
  std::optional<Vector> x = solve_from(*start, t, x_polynomial, q_polynomial, q_derivative, p, c);
  const bool known = std::find(last_.t.begin(), last_.t.begin() + last_.count, t) != last_.t.begin() + last_.count;
  if (x && !known) {
    // Rotated, not reallocated: the vectors keep their storage from row to row.
    std::rotate(last_.deviation.rbegin(), last_.deviation.rbegin() + 1, last_.deviation.rend());
    std::rotate(last_.t.rbegin(), last_.t.rbegin() + 1, last_.t.rend());
    last_.step = step;
    last_.count = std::min(last_.count + 1, kExtrapolationPoints);
    last_.t[0] = t;
    last_.deviation[0] = *x - x_polynomial;
  }
  return x;
}

std::optional<Vector> DenseOutput::solve_from(const Vector& x_guess, double t, const Vector& x_polynomial,
                                              const Vector& q_polynomial, const Vector& q_derivative,
                                              const Predicates& p, double c) {
  const CorrectorEquation equation{t, c, q_polynomial, q_derivative, x_polynomial, p};
  // Weighted on the polynomial's scale, not the iterate's: a diverging iterate must not loosen
  // its own test. The tolerance never asks for less than round-off in x.
  inverse_weight_.noalias() =
      ((options_.rtol + 100 * kEps) * x_polynomial.cwiseAbs() + absolute_tolerance_).cwiseInverse();
  // A row next to the last: modified Newton, on the factorization held if it is close, while
  // it contracts fast.
  Vector x = x_guess;
  const auto factored = newton_.factor(t, x, p, c, kKeptMatrixDrift);
  if (factored != NewtonMatrix::Outcome::ok && factored != NewtonMatrix::Outcome::kept) return std::nullopt;
  double previous_norm = std::numeric_limits<double>::infinity();
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    ++statistics_.newton_iterations;
    corrector_correction(newton_, equation, x, residual_, delta_);
    x -= delta_;
    const double norm = weighted_max_norm(delta_, inverse_weight_);
    if (!std::isfinite(norm)) break;
    const double rate = norm / previous_norm;
    if (rate > kFastContraction) break;
    // The corrections still to come, from the contraction so far (IDA's test); the first
    // correction, with no rate yet, counts as it is.
    if ((iteration == 0 ? norm : rate / (1 - rate) * norm) <= kConvergedNorm) {
      previous_iterate_.noalias() = x + delta_;
      if (newton_.currents_converged(previous_iterate_, x, options_.rtol)) return x;
    }
    if (newton_.evaluate(t, x, p) != EvalStatus::ok) break;
    previous_norm = norm;
  }
  // Otherwise damped Newton from the guess.
  x = x_guess;
  if (solve_damped(newton_, statistics_, equation, inverse_weight_, kConvergedNorm, options_.rtol, kMaxIterations, x) !=
      NewtonOutcome::converged)
    return std::nullopt;
  return x;
}

}  // namespace padae
