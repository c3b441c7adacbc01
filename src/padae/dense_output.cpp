#include "padae/dense_output.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include "padae/norms.hpp"

namespace padae {

namespace {

constexpr int kMaxIterations = 100;      // junctions far from their solution need many
constexpr double kConvergedNorm = 1e-2;  // Newton correction, in tolerance units
constexpr double kRefactorRate = 0.1;    // refactor when Newton contracts slower than this
// The factorization held serves the next row while every entry of the matrix at Newton's start
// is within this fraction of it: modified Newton then contracts about as fast as on a fresh
// matrix, so a small first correction is as telling. A matrix from another operating point
// can be far stiffer (a diode that has since turned off): a small correction on it proves
// nothing.
constexpr double kKeptMatrixDrift = 0.1;
constexpr double kEps = std::numeric_limits<double>::epsilon();

}  // namespace

DenseOutput::DenseOutput(System& system, Statistics& statistics, const Options& options,
                         const Vector& absolute_tolerance)
    : statistics_(statistics),
      newton_(system, statistics, absolute_tolerance / options.rtol),
      options_(options),
      absolute_tolerance_(absolute_tolerance) {}

std::optional<Vector> DenseOutput::solve(double t, const Vector& x_guess, const Vector& x_polynomial,
                                         const Vector& q_polynomial, const Vector& q_derivative,
                                         const Predicates& p, double c) {
  if (!(c > 0) || !std::isfinite(c)) return std::nullopt;
  Vector x = x_guess;
  // Weighted on the polynomial's scale, not the iterate's: a diverging iterate must not loosen
  // its own test. The tolerance never asks for less than round-off in x.
  inverse_weight_.noalias() =
      ((options_.rtol + 100 * kEps) * x_polynomial.cwiseAbs() + absolute_tolerance_).cwiseInverse();
  double keep_within = kKeptMatrixDrift;  // only the first factorization may keep the one held
  bool refactor = true;
  double previous_norm = std::numeric_limits<double>::infinity();
  previous_delta_.setZero(x.size());
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    if (refactor) {
      if (newton_.factor(t, x, p, c, std::exchange(keep_within, 0.0)) != NewtonMatrix::Outcome::ok)
        return std::nullopt;
    } else if (newton_.evaluate(t, x, p) != EvalStatus::ok) {
      return std::nullopt;
    }
    ++statistics_.newton_iterations;
    const Load& load = newton_.load();
    delta_.noalias() = q_derivative + c * (load.q - q_polynomial) + load.f;
    for (int i : newton_.auxiliary_unknowns()) delta_[i] = x[i] - x_polynomial[i];
    newton_.solve(delta_);
    x -= delta_;
    const double norm = weighted_max_norm(delta_, inverse_weight_);
    if (!std::isfinite(norm)) return std::nullopt;
    // Converged on the correction itself: far from the solution a rate estimated from two
    // corrections proves nothing (a junction's current falling back by decades in one step).
    if (norm <= kConvergedNorm) return x;
    const double rate = norm / previous_norm;
    // Within the tolerance, no longer contracting on a fresh matrix, and turning back: the
    // round-off floor of a tight tolerance, not a failure. A junction creeping toward its
    // solution (one thermal voltage per iteration) keeps its direction and is not taken.
    const double direction = delta_.cwiseProduct(inverse_weight_).dot(previous_delta_.cwiseProduct(inverse_weight_));
    if (refactor && norm <= 1 && rate >= 0.5 && direction < 0) return x;
    refactor = rate > kRefactorRate;
    previous_norm = norm;
    std::swap(previous_delta_, delta_);
  }
  return std::nullopt;
}

}  // namespace padae
