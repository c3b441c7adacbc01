// SUNDIALS IDA on a padae::System: the benchmarks' independent integrator for the same model
// code. IDA's residual is F(t, y, y') = (dq/dx) y' + f(t, y) with the charge matrix dq/dx taken
// once (constant in every system given to it: the paper's examples, TRANSAMP, circuits of linear
// capacitors and inductors); auxiliary unknowns get y' = 0. The guards are IDA's root functions.
// At a root the predicates flip in the direction the guard was heading (convention (9)), the jump
// x += X e is applied, the predicates are iterated to a fixed point, and IDA restarts with
// IDAReInit + IDACalcIC (IDA_YA_YDP_INIT: algebraic unknowns and derivatives made consistent).
// IDA's linear solver is its dense one: these systems have 2 to a few dozen unknowns.
#pragma once

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "padae/system.hpp"

namespace ida_bench {

using padae::Predicates;
using padae::Vector;

// IDA's work, summed over its restarts.
struct Counters {
  long steps = 0, rejected = 0, newton = 0, jacobians = 0, factorizations = 0, residuals = 0;
};

struct IdaSettings {
  double rtol = 1e-6;
  Vector atol;  // per unknown
  // q_i = x_i on differential rows (the paper's semi-explicit forms), else dq/dx at the start.
  bool semi_explicit = false;
  // Leave algebraic unknowns out of the error test (padae tests the dynamic rows only).
  bool suppress_algebraic = true;
  // The start made consistent as at a restart (algebraic unknowns re-solved, y' found), else
  // x0 kept as given and y' by least squares on the equations and their hidden constraints.
  bool consistent_start = false;
  long max_steps = 300000;
  // Newton iterations per step attempt, failed Newton and error test attempts per step, and
  // IDACalcIC's Newton iterations (IDA's defaults: 4, 10, 10, 10).
  int max_newton_iterations = 4;
  int max_newton_failures = 10;
  int max_error_test_failures = 10;
  int max_initial_condition_iterations = 10;
  // IDACalcIC's Newton converges to this fraction of the error weights (IDA's default 0.0033).
  double initial_condition_tolerance = 0.0033;
  // Consistent y and y' (IDA_YA_YDP_INIT's problem) by a Newton whose steps the model limits
  // (System::newton_step_fraction: a junction's pnjlim) instead of IDACalcIC's line search, which
  // gives up on a junction taken from deep reverse bias into conduction.
  bool limited_newton_initial_conditions = false;
};

enum class Outcome { reached, root, stop, failed };

class IdaRun {
 public:
  // span: the run's length, for IDACalcIC's first output time.
  IdaRun(padae::System& model, double t0, const Vector& x0, const Predicates& p0, double span,
         const IdaSettings& settings);
  ~IdaRun();
  IdaRun(const IdaRun&) = delete;
  IdaRun& operator=(const IdaRun&) = delete;

  bool ok() const { return failure_.empty(); }
  const std::string& failure() const { return failure_; }

  // Integrates towards tout, never past tstop: tout reached (IDA's interpolant there), a guard's
  // root, or tstop reached.
  Outcome advance(double tout, double tstop);
  // One of IDA's own steps, never past tstop.
  Outcome step(double tstop);
  // IDA's interpolant within its last step.
  Vector interpolate(double t);
  // At a root: whether a predicate flipped (a guard returning to its predicate's side is no
  // event); if so the jumps, the fixed point and the restart are done. first_flipped: the first
  // predicate that flipped.
  bool event(int& first_flipped);
  // A restart at the present t (a source's corner, or after an event's flips and jumps); `where`
  // completes the failure message.
  void restart(const std::string& where);

  double t() const { return t_; }
  Vector y() const;
  Vector yp() const;
  const Predicates& predicates() const { return p_; }
  // The charge matrix still describes q at x (IDA's residual assumes it constant).
  bool charges_unchanged(const Vector& x);
  Counters counters();

  // IDA's callbacks.
  int residual(double t, N_Vector y, N_Vector yp, N_Vector r);
  int jacobian(double cj, N_Vector y, double t, SUNMatrix J);
  int roots(double t, N_Vector y, double* g);

 private:
  void load_at(N_Vector y, bool jacobian);
  // f and the dense df/dx and dq/dx at (t, x) under the present predicates.
  padae::EvalStatus load_dense(double t, const Vector& x, Vector& f, Eigen::MatrixXd& df_dx, Eigen::MatrixXd& dq_dx);
  Eigen::MatrixXd charge_matrix(double t, const Vector& x);
  Vector consistent_rate(double t, const Vector& x);
  bool limited_newton_ic();
  Outcome solve(double tout, double tstop, int task);
  void fail(const std::string& why);

  padae::System& model_;
  IdaSettings settings_;
  int n_;
  double span_;
  Eigen::MatrixXd charge_;
  Predicates p_;
  padae::Load load_;
  Vector x_;
  Vector guards_, guards_ahead_;
  std::vector<int> root_signs_;
  double t_;
  std::string failure_;
  Counters total_;
  SUNContext context_ = nullptr;
  N_Vector y_ = nullptr, yp_ = nullptr, id_ = nullptr, interpolated_ = nullptr;
  SUNMatrix matrix_ = nullptr;
  SUNLinearSolver solver_ = nullptr;
  void* ida_ = nullptr;
};

}  // namespace ida_bench
