// Dense output: the state inside an accepted step, for writing.
//
// The step's interpolating polynomial is error-controlled only for the charges q of the
// dynamic rows. The unknowns no error test sees (algebraic ones, and hidden algebraic
// directions such as a floating capacitor's common mode) can be far off on it: a node behind
// a junction that is nearly off moves by volts for microvolts of its charges. The state
// written is instead the solution of the step's own corrector equation at t, with the
// polynomial in place of the predictor:
//     q'_poly(t) + c (q(x) - q_poly(t)) + f(t, x) = 0,    c = 1/h, h the step's length.
// Algebraic rows are solved exactly; a dynamic row's q stays within h times the polynomial's
// residual there (the size of the local error) of q_poly; a mode faster than the step is
// damped as the integration's backward differences damp it. The equation is as well
// conditioned as the corrector's, and at the step's end its solution is the corrector's.
#pragma once

#include <optional>

#include "padae/integrator.hpp"
#include "padae/newton_matrix.hpp"

namespace padae {

class DenseOutput {
 public:
  DenseOutput(System& system, const Options& options, const Vector& absolute_tolerance);

  // x at t inside a step of length h taken in mode p; the polynomial gives x_polynomial
  // (Newton's start, and the value of auxiliary unknowns), q_polynomial and q_derivative.
  // Empty where Newton fails (the caller keeps the polynomial).
  std::optional<Vector> solve(double t, const Vector& x_polynomial, const Vector& q_polynomial,
                              const Vector& q_derivative, const Predicates& p, double h);

 private:
  Statistics statistics_;  // its own: writing output never changes the integration's counts
  NewtonMatrix newton_;    // kept from row to row while it stays close to the matrix at x
  const Options& options_;
  const Vector& absolute_tolerance_;
  Vector delta_, inverse_weight_;
};

}  // namespace padae
