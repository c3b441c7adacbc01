// The solution inside an accepted step: what a step of the same order from the same history
// would reach at an inner time t. Written as dense output and used to locate events.
//
// The step's interpolating polynomial S (IDA's) is error-controlled only for the charges q of
// the dynamic rows. The unknowns no error test sees (algebraic ones, and hidden algebraic
// directions such as a floating capacitor's common mode) can be far off on it: a node behind a
// junction that is nearly off moves by volts for microvolts of its charges, and a source's node
// between the step's points is off by the polynomial's error in the source. Holding S's
// charges and solving for the rest turns their interpolation error into volts where the
// unknowns are flat in the charges. The BDF step from the step's start to t instead is
//     S'(t) + c (q(x) - S(t)) + f(t, x) = 0,    c = sum_j 1 / (t - t_j),
// t_j the step's start and the points before it that S passes through: the polynomial through
// (t, q(x)) and those points differs from S by a multiple of prod_j (t - t_j). Algebraic rows
// are solved exactly, q moves from S(t) by the step's own local error, a mode faster than the
// step is damped as the integration damps it, and at the step's end the solution is the
// corrector's.
#pragma once

#include <array>
#include <optional>

#include "padae/integrator.hpp"
#include "padae/newton_matrix.hpp"

namespace padae {

class DenseOutput {
 public:
  // Its Newton work is counted in statistics.
  DenseOutput(System& system, Statistics& statistics, const Options& options,
              const Vector& absolute_tolerance);

  // x at t inside step number `step` (taken in mode p), for the c above; S gives x_polynomial
  // (the value of auxiliary unknowns), q_polynomial and q_derivative. Newton starts from
  // x_guess if given, else from S plus the solution's distance from S extrapolated from the
  // last solutions inside the same step (that distance is smooth in t, and can be volts on a
  // floating node's common mode), else from S. Empty where Newton fails.
  std::optional<Vector> solve(long step, double t, const Vector* x_guess, const Vector& x_polynomial,
                              const Vector& q_polynomial, const Vector& q_derivative,
                              const Predicates& p, double c);

  // NewtonMatrix::charge_determined on this solver's matrix (its factorization is kept).
  EvalStatus charge_determined(double t, const Vector& x, const Predicates& p, std::vector<char>& out) {
    return newton_.charge_determined(t, x, p, out);
  }

 private:
  std::optional<Vector> solve_from(const Vector& x_guess, double t, const Vector& x_polynomial,
                                   const Vector& q_polynomial, const Vector& q_derivative, const Predicates& p,
                                   double c);

  Statistics& statistics_;
  NewtonMatrix newton_;    // kept from row to row while it stays close to the matrix at x
  const Options& options_;
  const Vector& absolute_tolerance_;
  Vector residual_, delta_, inverse_weight_, shifted_start_;
  Vector previous_iterate_;  // solve_from()'s, for System::currents_converged
  // The last solutions inside step number `step`, newest first: their distances from S.
  static constexpr int kExtrapolationPoints = 3;
  struct Solutions {
    long step = -1;
    int count = 0;
    std::array<double, kExtrapolationPoints> t{};
    std::array<Vector, kExtrapolationPoints> deviation;
  } last_;
};

}  // namespace padae
