#include "padae/dense_output.hpp"

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
  const Vector* start = x_guess ? x_guess : &x_polynomial;
  if (!x_guess && last_.step == step) {
    shifted_start_ = last_.x + (x_polynomial - last_.x_polynomial);
    start = &shifted_start_;
  }
  std::optional<Vector> x = solve_from(*start, t, x_polynomial, q_polynomial, q_derivative, p, c);
  if (x) {
    // Assigned in place: the vectors keep their storage from row to row.
    last_.step = step;
    last_.x = *x;
    last_.x_polynomial = x_polynomial;
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
    if ((iteration == 0 ? norm : rate / (1 - rate) * norm) <= kConvergedNorm) return x;
    if (newton_.evaluate(t, x, p) != EvalStatus::ok) break;
    previous_norm = norm;
  }
  // Otherwise damped Newton from the guess.
  x = x_guess;
  if (solve_damped(newton_, statistics_, equation, inverse_weight_, kConvergedNorm, kMaxIterations, x) !=
      NewtonOutcome::converged)
    return std::nullopt;
  return x;
}

}  // namespace padae
