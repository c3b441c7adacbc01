// The model side of a Newton iteration: loads f and q at a point, forms the iteration matrix
// df/dx + cj dq/dx on the system's pattern (analytic or by finite differences) and factors it.
// Shared by the BDF corrector, the jump re-initialization and the steady-state solver.
#pragma once

#include <optional>
#include <vector>

#include "padae/integrator.hpp"
#include "padae/sparse_lu.hpp"

namespace padae {

class NewtonMatrix {
 public:
  // typical: a magnitude per unknown below which it counts as small (the absolute tolerances);
  // it sizes the finite-difference increments.
  NewtonMatrix(System& system, Statistics& statistics, const Vector& typical);

  // f and q at (t, x, p) into load(); no derivatives.
  EvalStatus evaluate(double t, const Vector& x, const Predicates& p);
  // f, q and their derivatives at (t, x, p); then factors df/dx + cj dq/dx (rows of auxiliary
  // unknowns replaced by identity rows). False with a reason when the model fails or the matrix
  // is singular.
  enum class Outcome { ok, kept, outside_domain, singular };
  // keep_within > 0: keeps the factorization it holds (Outcome::kept) while its drift from the
  // matrix loaded now is at most keep_within (see drift()). A constant Jacobian
  // (System::constant_jacobian) is loaded once per mode, and a factorization of the same matrix
  // (same mode, same cj) is not repeated.
  Outcome factor(double t, const Vector& x, const Predicates& p, double cj, double keep_within = 0);
  // df/dx + cj dq/dx + shift I: pseudo-transient continuation toward a steady state (cj = 0),
  // inverse iteration toward what a singular matrix leaves undetermined.
  Outcome factor_shifted(double t, const Vector& x, const Predicates& p, double shift, double cj = 0);
  // As factor(), for the blend (1 - lambda) * system(p_from) + lambda * system(p_to) used by the
  // continuation in re-initialization. Leaves load() holding the blended f and q.
  Outcome factor_blend(double t, const Vector& x, const Predicates& p_from, const Predicates& p_to,
                       double lambda, double cj);

  void solve(Vector& b) const { lu_.solve(b); }
  // After factor() kept the factorization it held: J_held^-1 (J_held - J_now) d into out, for a
  // correction d made on it (J_now = df/dx + cj dq/dx as that call loaded it), the first-order
  // difference between d and the correction J_now would make. drift() compares row by row and
  // misses a change beside a larger entry: a junction factored in hard conduction, now nearly
  // off, behind its series resistance (RS's 200 S leads the row while the junction's conductance
  // falls a thousandfold). Along d it shows: half of d's size where J_held is twice as stiff.
  void kept_mismatch(const Vector& d, double cj, Vector& out) const;
  // The fraction of the step from x to x_next the model accepts (System::newton_step_fraction).
  double step_fraction(const Vector& x, const Vector& x_next) const {
    return system_.newton_step_fraction(x, x_next);
  }
  // System::currents_converged.
  bool currents_converged(const Vector& x_before, const Vector& x_after, double rtol) const {
    return system_.currents_converged(x_before, x_after, rtol);
  }
  const Load& load() const { return load_; }
  // The first row whose f or q in load() is not finite, -1 if none: the equation that names
  // the element a model evaluation outside its domain came from.
  int first_non_finite_row() const;
  // |dq/dx| summed into row weights: sum_j |dq_ij/dx_j| * scale_j (zero for algebraic rows).
  void charge_scale(const Vector& scale, Vector& out) const;
  // Per unknown, whether some row's charge depends on it alone (that row of dq/dx at (t, x, p)
  // has its one non-zero in the unknown's column): the unknown is then a function of that
  // charge, as a grounded capacitor's node voltage or an inductor's current.
  EvalStatus charge_determined(double t, const Vector& x, const Predicates& p, std::vector<char>& out);
  // Zeroes the entries of v on algebraic rows (no dq/dx in the last factorization).
  void keep_dynamic_rows(Vector& v) const;
  // Whether |v_i| <= tolerances / inverse_weight_i + roundoffs * r_i for every i, r what
  // rounding alone makes of a Newton correction at x in the last factorization: the rounding of
  // the residual's terms, eps (|J| |x| + |other_terms|) row by row (other_terms: what else the
  // residual sums, c q_anchor and q'), with signs that do not cancel systematically, through
  // J^-1. A correction within it is the residual's noise: x solves the equations to working
  // precision. Differential unknowns get that slack only where it moves no charge (dq/dx v
  // within the charges' tolerances) and where rounding still resolves the direction: along
  // the common mode of capacitors between nodes that only a large resistance ties down (a
  // floating secondary held by 1 MOhm: C/h swamps its 1 uS in every row of the matrix).
  bool within_roundoff(const Vector& v, double tolerances, const Vector& inverse_weight, double roundoffs,
                       const Vector& x, const Vector& other_terms) const;
  // Whether the factorization held is of df/dx + cj dq/dx in mode p exactly: a constant
  // Jacobian factored in that mode at that cj, on which Newton solves the (affine) equations in
  // one correction.
  bool factored_exactly(const Predicates& p, double cj) const {
    return system_.constant_jacobian() && factored_cj_ == cj && factored_mode_ == p;
  }
  int singular_column() const { return lu_.singular_column(); }
  int determinant_sign() const { return lu_.determinant_sign(); }
  bool is_auxiliary(int unknown) const { return auxiliary_[unknown]; }
  const std::vector<int>& auxiliary_unknowns() const { return auxiliary_list_; }

 private:
  EvalStatus load_with_derivatives(double t, const Vector& x, const Predicates& p, Load& out);
  EvalStatus finite_difference_derivatives(double t, const Vector& x, const Predicates& p,
                                           Load& out);
  Outcome factor_loaded();
  // |J^-1 eps (|J| |x| + |other_terms|)|, row signs scrambled: what rounding makes of a Newton
  // correction at x in the last factorization, in size.
  void rounding_through_inverse(const Vector& x, const Vector& other_terms, Vector& out) const;
  // out += |A| |v|, A the matrix with these values on the pattern.
  void add_absolute_product(const std::vector<double>& values, const Vector& v, Vector& out) const;
  // The factorization's drift from df/dx + cj dq/dx as loaded now: the largest, over the rows,
  // of the row's largest |factored - now| over its largest |now|; infinite when the
  // factorization is of another mode or not of factor()'s form. Row by row because what moves
  // Newton is an entry's weight in its equation: a reverse-biased junction's conductance may
  // change a hundredfold beside a resistor's and matter nowhere. Below 1 in every row the
  // factorization is nowhere twice as stiff as the matrix now.
  double drift(const Predicates& p, double cj) const;
  // Entry k of df/dx + cj dq/dx as loaded now.
  double loaded_entry(std::size_t k, double cj) const { return load_.df_dx[k] + cj * load_.dq_dx[k]; }

  System& system_;
  Statistics& statistics_;
  const Pattern& pattern_;
  SparseLu lu_;
  Load load_;
  Load blend_;            // second load for the continuation blend
  Load perturbed_;        // scratch for finite differences
  std::vector<double> matrix_;
  std::vector<double> dq_dx_;      // dq/dx of the last factorization
  mutable Vector row_scale_;       // scratch of drift()
  mutable Vector roundoff_;        // scratch of within_roundoff()
  mutable Vector rounding_, signed_rounding_;  // scratch of rounding_through_inverse()
  mutable Vector charge_move_;     // scratch of within_roundoff()
  std::vector<char> auxiliary_;
  std::vector<int> auxiliary_list_;
  std::vector<int> diagonal_;      // value index of (i, i)
  std::vector<std::vector<int>> column_groups_;  // structurally orthogonal columns, for FD
  Vector typical_;
  Predicates factored_mode_;
  double factored_cj_ = 0;  // 0: the factorization held is not of factor()'s form
  // A constant Jacobian: the mode whose derivatives load_ holds (none before the first load).
  std::optional<Predicates> derivatives_mode_;
};

}  // namespace padae
