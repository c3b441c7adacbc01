#include "ida_run.hpp"

#include <algorithm>
#include <cmath>

namespace ida_bench {

namespace {

using padae::EvalStatus;
using padae::UnknownKind;

int residual_callback(double t, N_Vector y, N_Vector yp, N_Vector r, void* user) {
  return static_cast<IdaRun*>(user)->residual(t, y, yp, r);
}

int jacobian_callback(double t, double cj, N_Vector y, N_Vector, N_Vector, SUNMatrix J, void* user, N_Vector,
                      N_Vector, N_Vector) {
  return static_cast<IdaRun*>(user)->jacobian(cj, y, t, J);
}

int roots_callback(double t, N_Vector y, N_Vector, double* g, void* user) {
  return static_cast<IdaRun*>(user)->roots(t, y, g);
}

Counters read_counters(void* ida) {
  long steps = 0, iterations = 0, jacobians = 0, setups = 0, error_fails = 0, newton_fails = 0, residuals = 0;
  IDAGetNumSteps(ida, &steps);
  IDAGetNumNonlinSolvIters(ida, &iterations);
  IDAGetNumJacEvals(ida, &jacobians);
  IDAGetNumLinSolvSetups(ida, &setups);
  IDAGetNumErrTestFails(ida, &error_fails);
  IDAGetNumNonlinSolvConvFails(ida, &newton_fails);
  IDAGetNumResEvals(ida, &residuals);
  return {steps, error_fails + newton_fails, iterations, jacobians, setups, residuals};
}

Counters operator+(Counters a, const Counters& b) {
  a.steps += b.steps;
  a.rejected += b.rejected;
  a.newton += b.newton;
  a.jacobians += b.jacobians;
  a.factorizations += b.factorizations;
  a.residuals += b.residuals;
  return a;
}

}  // namespace

IdaRun::IdaRun(padae::System& model, double t0, const Vector& x0, const Predicates& p0, double span,
               const IdaSettings& settings)
    : model_(model),
      settings_(settings),
      n_(model.size()),
      span_(span),
      p_(p0),
      x_(Vector::Zero(n_)),
      guards_(model.predicate_count()),
      guards_ahead_(model.predicate_count()),
      root_signs_(static_cast<std::size_t>(std::max(model.predicate_count(), 1))),
      t_(t0) {
  load_.df_dx.assign(static_cast<std::size_t>(model.pattern().nonzeros()), 0.0);
  load_.dq_dx.assign(load_.df_dx.size(), 0.0);
  charge_ = Eigen::MatrixXd::Zero(n_, n_);
  if (settings_.semi_explicit) {
    for (int i = 0; i < n_; ++i)
      if (model.kind(i) == UnknownKind::differential) charge_(i, i) = 1;
  } else {
    charge_ = charge_matrix(t0, x0);
  }

  SUNContext_Create(nullptr, &context_);
  y_ = N_VNew_Serial(n_, context_);
  yp_ = N_VNew_Serial(n_, context_);
  id_ = N_VNew_Serial(n_, context_);
  interpolated_ = N_VNew_Serial(n_, context_);
  N_Vector atol = N_VNew_Serial(n_, context_);
  for (int i = 0; i < n_; ++i) {
    NV_Ith_S(y_, i) = x0[i];
    NV_Ith_S(yp_, i) = 0;
    NV_Ith_S(id_, i) = model.kind(i) == UnknownKind::algebraic ? 0.0 : 1.0;
    NV_Ith_S(atol, i) = settings_.atol[i];
  }
  if (!settings_.semi_explicit && !settings_.consistent_start) {
    const Vector rate = consistent_rate(t0, x0);
    for (int i = 0; i < n_; ++i) NV_Ith_S(yp_, i) = rate[i];
  }
  ida_ = IDACreate(context_);
  matrix_ = SUNDenseMatrix(n_, n_, context_);
  solver_ = SUNLinSol_Dense(y_, matrix_, context_);
  IDAInit(ida_, residual_callback, t0, y_, yp_);
  IDASVtolerances(ida_, settings_.rtol, atol);
  N_VDestroy(atol);
  IDASetUserData(ida_, this);
  IDASetLinearSolver(ida_, solver_, matrix_);
  if (model.analytic_jacobian()) IDASetJacFn(ida_, jacobian_callback);
  IDASetId(ida_, id_);
  IDASetSuppressAlg(ida_, settings_.suppress_algebraic ? SUNTRUE : SUNFALSE);
  IDASetMaxNumSteps(ida_, settings_.max_steps);
  IDASetMaxNonlinIters(ida_, settings_.max_newton_iterations);
  IDASetMaxConvFails(ida_, settings_.max_newton_failures);
  IDASetMaxErrTestFails(ida_, settings_.max_error_test_failures);
  IDASetMaxNumItersIC(ida_, settings_.max_initial_condition_iterations);
  IDASetNonlinConvCoefIC(ida_, settings_.initial_condition_tolerance);
  if (model.predicate_count() > 0) {
    IDARootInit(ida_, model.predicate_count(), roots_callback);
    IDASetNoInactiveRootWarn(ida_);
  }
  if (settings_.semi_explicit || settings_.consistent_start) restart("at t0");
}

IdaRun::~IdaRun() {
  IDAFree(&ida_);
  SUNLinSolFree(solver_);
  SUNMatDestroy(matrix_);
  N_VDestroy(y_);
  N_VDestroy(yp_);
  N_VDestroy(id_);
  N_VDestroy(interpolated_);
  SUNContext_Free(&context_);
}

void IdaRun::fail(const std::string& why) {
  if (failure_.empty()) failure_ = why;
}

Vector IdaRun::y() const {
  Vector v(n_);
  for (int i = 0; i < n_; ++i) v[i] = NV_Ith_S(y_, i);
  return v;
}

Vector IdaRun::yp() const {
  Vector v(n_);
  for (int i = 0; i < n_; ++i) v[i] = NV_Ith_S(yp_, i);
  return v;
}

Counters IdaRun::counters() { return total_ + read_counters(ida_); }

void IdaRun::load_at(N_Vector y, bool jacobian) {
  const double* yd = N_VGetArrayPointer(y);
  for (int i = 0; i < n_; ++i) x_[i] = yd[i];
  load_.f.setZero(n_);
  load_.q.setZero(n_);
  load_.jacobian_requested = jacobian;
  if (jacobian) {
    std::fill(load_.df_dx.begin(), load_.df_dx.end(), 0.0);
    std::fill(load_.dq_dx.begin(), load_.dq_dx.end(), 0.0);
  }
}

int IdaRun::residual(double t, N_Vector y, N_Vector yp, N_Vector r) {
  load_at(y, false);
  if (model_.load(t, x_, p_, load_) != EvalStatus::ok) return 1;  // recoverable: IDA cuts the step
  const double* ypd = N_VGetArrayPointer(yp);
  double* rd = N_VGetArrayPointer(r);
  for (int i = 0; i < n_; ++i) {
    if (model_.kind(i) == UnknownKind::auxiliary) {
      rd[i] = ypd[i];
      continue;
    }
    double s = load_.f[i];
    for (int j = 0; j < n_; ++j) s += charge_(i, j) * ypd[j];
    rd[i] = s;
  }
  return 0;
}

int IdaRun::jacobian(double cj, N_Vector y, double t, SUNMatrix J) {
  load_at(y, true);
  if (model_.load(t, x_, p_, load_) != EvalStatus::ok) return 1;
  SUNMatZero(J);
  const auto& starts = model_.pattern().column_starts();
  const auto& rows = model_.pattern().row_indices();
  for (int column = 0; column < n_; ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k)
      if (model_.kind(rows[k]) != UnknownKind::auxiliary) SM_ELEMENT_D(J, rows[k], column) += load_.df_dx[k];
  for (int i = 0; i < n_; ++i) {
    if (model_.kind(i) == UnknownKind::auxiliary) {
      SM_ELEMENT_D(J, i, i) = cj;
      continue;
    }
    for (int j = 0; j < n_; ++j) SM_ELEMENT_D(J, i, j) += cj * charge_(i, j);
  }
  return 0;
}

int IdaRun::roots(double t, N_Vector y, double* g) {
  const double* yd = N_VGetArrayPointer(y);
  for (int i = 0; i < n_; ++i) x_[i] = yd[i];
  if (model_.guards(t, x_, guards_) != EvalStatus::ok) return 1;
  for (int k = 0; k < guards_.size(); ++k) g[k] = guards_[k];
  return 0;
}

EvalStatus IdaRun::load_dense(double t, const Vector& x, Vector& f, Eigen::MatrixXd& df_dx, Eigen::MatrixXd& dq_dx) {
  padae::Load load;
  load.f.setZero(n_);
  load.q.setZero(n_);
  load.df_dx.assign(load_.df_dx.size(), 0.0);
  load.dq_dx.assign(load_.df_dx.size(), 0.0);
  load.jacobian_requested = true;
  const EvalStatus status = model_.load(t, x, p_, load);
  f = load.f;
  df_dx = Eigen::MatrixXd::Zero(n_, n_);
  dq_dx = Eigen::MatrixXd::Zero(n_, n_);
  const auto& starts = model_.pattern().column_starts();
  const auto& rows = model_.pattern().row_indices();
  for (int column = 0; column < n_; ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k) {
      df_dx(rows[k], column) = load.df_dx[k];
      dq_dx(rows[k], column) = load.dq_dx[k];
    }
  return status;
}

Eigen::MatrixXd IdaRun::charge_matrix(double t, const Vector& x) {
  Vector f;
  Eigen::MatrixXd df_dx, dq_dx;
  load_dense(t, x, f, df_dx, dq_dx);
  return dq_dx;
}

bool IdaRun::charges_unchanged(const Vector& x) {
  if (settings_.semi_explicit) return true;
  return (charge_matrix(t_, x) - charge_).cwiseAbs().maxCoeff() <= 1e-12 * charge_.cwiseAbs().maxCoeff();
}

// y'(t0) consistent with an index-1 charge-form DAE with constant Q = dq/dx: Q y' = -f on the
// range of Q, and the hidden constraints n^T f(t, y) = 0 (n in the left null space of Q)
// differentiated: n^T (df/dx y' + df/dt) = 0. Least squares on the stacked (consistent) system.
Vector IdaRun::consistent_rate(double t, const Vector& x) {
  auto f_at = [&](double tt) {
    padae::Load load;
    load.f.setZero(n_);
    load.q.setZero(n_);
    model_.load(tt, x, p_, load);
    return Vector(load.f);
  };
  const double dt = 1e-7;
  Vector dfdt = (f_at(t + dt) - f_at(t - dt)) / (2 * dt);
  Vector f;
  Eigen::MatrixXd J, dq_dx;
  load_dense(t, x, f, J, dq_dx);
  Eigen::FullPivLU<Eigen::MatrixXd> lu(charge_.transpose());
  Eigen::MatrixXd null = lu.kernel();  // columns: left null vectors of Q
  if (lu.rank() == n_) null.resize(n_, 0);
  Eigen::MatrixXd S(n_ + null.cols(), n_);
  Vector rhs(n_ + null.cols());
  S.topRows(n_) = charge_;
  rhs.head(n_) = -f;
  if (null.cols() > 0) {
    S.bottomRows(null.cols()) = null.transpose() * J;
    rhs.tail(null.cols()) = -null.transpose() * dfdt;
  }
  return S.colPivHouseholderQr().solve(rhs);
}

// IDA starts again at t_ from y_ and y_' made consistent: by IDACalcIC, which works on the
// state IDA holds (IDAReInit first), or by the limited Newton, whose result IDA then takes.
void IdaRun::restart(const std::string& where) {
  total_ = total_ + read_counters(ida_);  // IDAReInit zeroes IDA's counters
  bool consistent = true;
  if (settings_.limited_newton_initial_conditions) {
    consistent = limited_newton_ic();
    IDAReInit(ida_, t_, y_, yp_);
  } else {
    IDAReInit(ida_, t_, y_, yp_);
    consistent = IDACalcIC(ida_, IDA_YA_YDP_INIT, t_ + 1e-3 * span_) == IDA_SUCCESS;
    if (consistent) IDAGetConsistentIC(ida_, y_, yp_);
  }
  if (!consistent) fail("IDACalcIC " + where);
}

// F(t, y, y') = Q y' + f(t, y) = 0 for the algebraic y and the other unknowns' y', with the
// differential y held; Newton's step scaled by the model's limit. Dense: a reference's sizes.
bool IdaRun::limited_newton_ic() {
  Vector x = y(), rate = yp(), f;
  Eigen::MatrixXd df_dx, dq_dx;
  double previous_worst = INFINITY;
  for (int iteration = 0; iteration < settings_.max_initial_condition_iterations; ++iteration) {
    if (load_dense(t_, x, f, df_dx, dq_dx) != EvalStatus::ok) return false;
    Vector r(n_);
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n_, n_);
    for (int i = 0; i < n_; ++i) {
      switch (model_.kind(i)) {
        case UnknownKind::auxiliary:
          r[i] = rate[i];
          J(i, i) = 1;
          break;
        case UnknownKind::algebraic:
          r[i] = f[i] + charge_.row(i).dot(rate);
          J.col(i) = df_dx.col(i);
          break;
        case UnknownKind::differential:
          r[i] = f[i] + charge_.row(i).dot(rate);
          J.col(i) = charge_.col(i);
          break;
      }
    }
    const Vector du = -J.fullPivLu().solve(r);
    Vector x_next = x;
    for (int i = 0; i < n_; ++i)
      if (model_.kind(i) == UnknownKind::algebraic) x_next[i] += du[i];
    const double fraction = model_.newton_step_fraction(x, x_next);
    double worst = 0;
    for (int i = 0; i < n_; ++i) {
      if (model_.kind(i) == UnknownKind::algebraic) {
        x[i] += fraction * du[i];
        worst = std::max(worst, std::abs(du[i]) / (settings_.rtol * std::abs(x[i]) + settings_.atol[i]));
      } else {
        rate[i] += fraction * du[i];
        worst = std::max(worst, std::abs(du[i]) * span_ / (settings_.rtol * std::abs(rate[i]) * span_ + settings_.atol[i]));
      }
    }
    if (!std::isfinite(worst)) return false;
    // Converged: the update is below the test, or within the weights and no longer shrinking
    // (the round-off of the residual, which is what stops it on a switch's 100 S branch).
    const bool stalled = worst <= 1 && worst >= 0.5 * previous_worst;
    previous_worst = fraction == 1 ? worst : INFINITY;
    if (fraction == 1 && (worst <= settings_.initial_condition_tolerance || stalled)) {
      for (int i = 0; i < n_; ++i) {
        NV_Ith_S(y_, i) = x[i];
        NV_Ith_S(yp_, i) = rate[i];
      }
      return true;
    }
  }
  return false;
}

Outcome IdaRun::advance(double tout, double tstop) { return solve(std::min(tout, tstop), tstop, IDA_NORMAL); }

Outcome IdaRun::step(double tstop) { return solve(tstop, tstop, IDA_ONE_STEP); }

Outcome IdaRun::solve(double tout, double tstop, int task) {
  if (!ok()) return Outcome::failed;
  // IDA forgets a stop time once it has stopped there: it is set before every call.
  IDASetStopTime(ida_, tstop);
  const int flag = IDASolve(ida_, tout, &t_, y_, yp_, task);
  if (flag == IDA_TSTOP_RETURN) return Outcome::stop;
  if (flag == IDA_ROOT_RETURN) return Outcome::root;
  if (flag == IDA_SUCCESS) return t_ >= tstop ? Outcome::stop : Outcome::reached;
  fail("IDASolve returned " + std::to_string(flag) + " at t = " + std::to_string(t_));
  return Outcome::failed;
}

Vector IdaRun::interpolate(double t) {
  IDAGetDky(ida_, t, 0, interpolated_);
  Vector out(n_);
  for (int i = 0; i < n_; ++i) out[i] = NV_Ith_S(interpolated_, i);
  return out;
}

bool IdaRun::event(int& first_flipped) {
  const int K = model_.predicate_count();
  IDAGetRootInfo(ida_, root_signs_.data());
  // A predicate flips in the direction its guard was heading (convention (9)); a guard that
  // returns to the side its predicate already says is no event.
  Vector e = Vector::Zero(K);
  first_flipped = -1;
  for (int k = 0; k < K; ++k) {
    const int r = root_signs_[static_cast<std::size_t>(k)];
    if (r != 0 && static_cast<bool>(p_[static_cast<std::size_t>(k)]) != (r > 0)) {
      e[k] = r > 0 ? 1 : -1;
      if (first_flipped < 0) first_flipped = k;
    }
  }
  if (first_flipped < 0) return false;
  // Jump x += X(t, x-, p-) e, flip, restart (IDAReInit + IDACalcIC), then the fixed point: a
  // guard with a definite sign against its predicate flips; a guard at zero (the one just
  // crossed, or one a jump left there) takes the side the new motion heads to, dg/dt along the
  // consistent y' (convention (9): an impact reverses the motion, the rod leaves the wall).
  int iteration = 0;
  std::vector<padae::JumpEntry> entries;
  for (; iteration < 50 && e.cwiseAbs().sum() > 0 && ok(); ++iteration) {
    Vector x = y();
    if (model_.has_jumps()) {
      entries.clear();
      model_.jump_matrix(t_, x, p_, entries);
      for (const auto& j : entries) x[j.row] += j.value * e[j.predicate];
    }
    for (int k = 0; k < K; ++k)
      if (e[k] != 0) p_[static_cast<std::size_t>(k)] = e[k] > 0;
    for (int i = 0; i < n_; ++i) NV_Ith_S(y_, i) = x[i];
    restart("after the event at t = " + std::to_string(t_));
    if (!ok()) break;
    x = y();
    const Vector xdot = yp();
    const double dt = 1e-7 * std::max(std::abs(t_), 1e-3);
    model_.guards(t_, x, guards_);
    model_.guards(t_ + dt, x + dt * xdot, guards_ahead_);
    e.setZero();
    const double tiny = 1e-9 * (1 + x.cwiseAbs().maxCoeff());
    for (int k = 0; k < K; ++k) {
      const bool want = std::abs(guards_[k]) > tiny ? guards_[k] > 0 : guards_ahead_[k] > guards_[k];
      if (want != static_cast<bool>(p_[static_cast<std::size_t>(k)])) e[k] = want ? 1 : -1;
    }
  }
  if (iteration == 50) fail("no predicate fixed point at t = " + std::to_string(t_));
  return true;
}

}  // namespace ida_bench
