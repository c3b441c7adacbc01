// The integrator alone against SUNDIALS IDA, same run: the same model code (a padae::System),
// the same initial state, tolerances and end time, and for the problems with events the same
// guards and jump matrix. padae handles events itself; IDA gets the guards as root functions
// (IDARootInit), and at every root this driver flips the predicates in the direction the guard
// was heading (convention (9)), applies the jump x += X e, iterates the predicates to a fixed
// point, and restarts IDA with IDAReInit + IDACalcIC (IDA_YA_YDP_INIT: algebraic unknowns and
// derivatives made consistent).
//
// Problems (each with a closed form or a published reference):
//   masses_jump      the paper's example (6): capture (jump of v) and contact, closed form
//   masses_momentum  the same motion in form (4), no jumps
//   escapement       example (7): kicks at upward zero crossings, closed-form kick times and
//                    post-kick velocities (damped period, return map)
//   pendulum         example (10): impacts on a wall, impact times by quadrature; stopped
//                    between the 6th and 7th impact (before the Zeno accumulation)
//   transistor_amp   the Bari test set's TRANSAMP, reference at t = 0.2 (smooth, stiff)
//
// Output: one JSON object on stdout. Per run: solver, rtol (atol = rtol, as the padae
// benchmark), correct digits (-log10 of the error measure the problem defines), CPU time per
// run (median over repetitions, CLOCK_PROCESS_CPUTIME_ID), counters, event-time error against
// the exact instants, and the event *location* error: the distance in time from the located
// instant to the root of the computed solution, |g(t, x-)| / |dg/dt|, relative to t.
//
// Usage: padae_ida_compare [min CPU seconds per configuration, default 0.2] [problem name]
// With IDA_COMPARE_EVENTS set, every event of every run is listed on stderr.
//
// IDA's linear solver is its dense one (these systems have 2 to 8 unknowns; padae uses KLU).
// The charge matrix dq/dx is constant in all these problems, so IDA's residual is
// F(t, y, y') = (dq/dx) y' + f(t, y); auxiliary unknowns get y' = 0.
#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "padae/integrator.hpp"
#include "padae/semi_explicit.hpp"
#include "paper_impacts.hpp"
#include "paper_masses.hpp"
#include "transistor_amplifier.hpp"

namespace {

using padae::EvalStatus;
using padae::Predicates;
using padae::UnknownKind;
using padae::Vector;

constexpr auto D = UnknownKind::differential;
constexpr auto A = UnknownKind::algebraic;
constexpr auto X = UnknownKind::auxiliary;

struct Event {
  double t;
  Vector x_before, x_after;
};

struct Run {
  bool ok = true;
  std::string failure;
  Vector x_end;
  double t_end = 0;
  std::vector<Event> events;
  long steps = 0, rejected = 0, newton = 0, jacobians = 0, factorizations = 0, residuals = 0;
  double location_error = 0;  // max over events of |g(t, x-)| / |dg/dt| / t
};

// The time from the located instant to the root of the computed solution: |g| / |dg/dt| with
// dg/dt by a difference along x' (the model's own rhs for semi-explicit systems, IDA's y').
double location_error(const padae::System& model, double t, const Vector& x, const Vector& xdot, int k) {
  const int K = model.predicate_count();
  Vector g0(K), g1(K);
  model.guards(t, x, g0);
  const double dt = 1e-7 * std::max(std::abs(t), 1e-3);
  model.guards(t - dt, x - dt * xdot, g1);
  const double slope = (g0[k] - g1[k]) / dt;
  if (slope == 0) return 0;
  return std::abs(g0[k] / slope) / std::max(std::abs(t), 1e-300);
}

// x' of a semi-explicit system's differential unknowns at (t, x, p): rhs = -f on those rows.
Vector semi_explicit_rate(padae::System& model, double t, const Vector& x, const Predicates& p) {
  const int n = model.size();
  padae::Load load;
  load.f.setZero(n);
  load.q.setZero(n);
  model.load(t, x, p, load);
  Vector rate = Vector::Zero(n);
  for (int i = 0; i < n; ++i)
    if (model.kind(i) == D) rate[i] = -load.f[i];
  return rate;
}

// IDA gives up after this many steps (TRANSAMP at tight tolerances would otherwise run for minutes).
constexpr long kMaxIdaSteps = 300000;

double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// --- padae --------------------------------------------------------------------------------------
Run run_padae(padae::System& model, const Vector& x0, double t0, double t_end, double rtol, bool semi_explicit) {
  padae::Options options;
  options.rtol = rtol;
  options.atol = rtol;
  options.time_scale = t_end - t0;
  padae::Integrator integrator(model, options);
  Run run;
  if (!integrator.initialize(t0, x0)) {
    run.ok = false;
    run.failure = integrator.failure().reason;
    return run;
  }
  while (integrator.time() < t_end) {
    const Predicates p_before = integrator.predicates();
    const padae::StepOutcome outcome = integrator.step(t_end);
    if (outcome.kind == padae::StepKind::failed) {
      run.ok = false;
      run.failure = integrator.failure().reason;
      break;
    }
    if (outcome.kind == padae::StepKind::event) {
      const padae::EventRecord& e = integrator.last_event();
      run.events.push_back({e.t, e.x_before, e.x_after});
      if (semi_explicit && !e.flips.empty()) {
        const Vector rate = semi_explicit_rate(model, e.t, e.x_before, p_before);
        run.location_error = std::max(run.location_error,
                                      location_error(model, e.t, e.x_before, rate, e.flips.front().predicate));
      }
    }
  }
  const padae::Statistics& s = integrator.statistics();
  run.x_end = integrator.state();
  run.t_end = integrator.time();
  run.steps = s.steps;
  run.rejected = s.rejected_error_test + s.rejected_newton + s.rejected_domain;
  run.newton = s.newton_iterations;
  run.jacobians = s.jacobians;
  run.factorizations = s.lu_factorizations;
  run.residuals = s.residual_evaluations;
  return run;
}

// --- IDA ----------------------------------------------------------------------------------------
struct IdaModel {
  padae::System& model;
  int n;
  Eigen::MatrixXd charge;  // dq/dx, constant
  Predicates p;
  padae::Load load;
  Vector x;
  bool analytic;
};

void load_at(IdaModel& m, N_Vector y, bool jacobian) {
  const double* yd = N_VGetArrayPointer(y);
  for (int i = 0; i < m.n; ++i) m.x[i] = yd[i];
  m.load.f.setZero(m.n);
  m.load.q.setZero(m.n);
  m.load.jacobian_requested = jacobian;
  if (jacobian) {
    std::fill(m.load.df_dx.begin(), m.load.df_dx.end(), 0.0);
    std::fill(m.load.dq_dx.begin(), m.load.dq_dx.end(), 0.0);
  }
}

int ida_residual(double t, N_Vector y, N_Vector yp, N_Vector r, void* user) {
  auto& m = *static_cast<IdaModel*>(user);
  load_at(m, y, false);
  if (m.model.load(t, m.x, m.p, m.load) != EvalStatus::ok) return 1;  // recoverable: IDA cuts the step
  const double* ypd = N_VGetArrayPointer(yp);
  double* rd = N_VGetArrayPointer(r);
  for (int i = 0; i < m.n; ++i) {
    if (m.model.kind(i) == X) {
      rd[i] = ypd[i];
      continue;
    }
    double s = m.load.f[i];
    for (int j = 0; j < m.n; ++j) s += m.charge(i, j) * ypd[j];
    rd[i] = s;
  }
  return 0;
}

int ida_jacobian(double t, double cj, N_Vector y, N_Vector, N_Vector, SUNMatrix J, void* user, N_Vector, N_Vector, N_Vector) {
  auto& m = *static_cast<IdaModel*>(user);
  load_at(m, y, true);
  if (m.model.load(t, m.x, m.p, m.load) != EvalStatus::ok) return 1;
  SUNMatZero(J);
  const auto& starts = m.model.pattern().column_starts();
  const auto& rows = m.model.pattern().row_indices();
  for (int column = 0; column < m.n; ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k)
      if (m.model.kind(rows[k]) != X) SM_ELEMENT_D(J, rows[k], column) += m.load.df_dx[k];
  for (int i = 0; i < m.n; ++i) {
    if (m.model.kind(i) == X) {
      SM_ELEMENT_D(J, i, i) = cj;
      continue;
    }
    for (int j = 0; j < m.n; ++j) SM_ELEMENT_D(J, i, j) += cj * m.charge(i, j);
  }
  return 0;
}

int ida_roots(double t, N_Vector y, N_Vector, double* g, void* user) {
  auto& m = *static_cast<IdaModel*>(user);
  const double* yd = N_VGetArrayPointer(y);
  for (int i = 0; i < m.n; ++i) m.x[i] = yd[i];
  Vector out(m.model.predicate_count());
  if (m.model.guards(t, m.x, out) != EvalStatus::ok) return 1;
  for (int k = 0; k < out.size(); ++k) g[k] = out[k];
  return 0;
}

// y'(t0) consistent with an index-1 charge-form DAE with constant Q = dq/dx: Q y' = -f on the
// range of Q, and the hidden constraints n^T f(t, y) = 0 (n in the left null space of Q)
// differentiated: n^T (df/dx y' + df/dt) = 0. Least squares on the stacked (consistent) system.
Vector consistent_rate(IdaModel& m, double t, const Vector& x) {
  const int n = m.n;
  auto f_at = [&](double tt) {
    padae::Load load;
    load.f.setZero(n);
    load.q.setZero(n);
    m.model.load(tt, x, m.p, load);
    return Vector(load.f);
  };
  Vector f = f_at(t);
  const double dt = 1e-7;
  Vector dfdt = (f_at(t + dt) - f_at(t - dt)) / (2 * dt);
  padae::Load load;
  load.f.setZero(n);
  load.q.setZero(n);
  load.df_dx.assign(static_cast<std::size_t>(m.model.pattern().nonzeros()), 0.0);
  load.dq_dx.assign(load.df_dx.size(), 0.0);
  load.jacobian_requested = true;
  m.model.load(t, x, m.p, load);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  const auto& starts = m.model.pattern().column_starts();
  const auto& rows = m.model.pattern().row_indices();
  for (int column = 0; column < n; ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k) J(rows[k], column) = load.df_dx[k];
  Eigen::FullPivLU<Eigen::MatrixXd> lu(m.charge.transpose());
  Eigen::MatrixXd null = lu.kernel();  // columns: left null vectors of Q
  if (lu.rank() == n) null.resize(n, 0);
  Eigen::MatrixXd S(n + null.cols(), n);
  Vector rhs(n + null.cols());
  S.topRows(n) = m.charge;
  rhs.head(n) = -f;
  if (null.cols() > 0) {
    S.bottomRows(null.cols()) = null.transpose() * J;
    rhs.tail(null.cols()) = -null.transpose() * dfdt;
  }
  return S.colPivHouseholderQr().solve(rhs);
}

Run run_ida(padae::System& model, const Vector& x0, double t0, double t_end, double rtol, bool semi_explicit) {
  Run run;
  const int n = model.size();
  IdaModel m{model, n, Eigen::MatrixXd::Zero(n, n), Predicates(static_cast<std::size_t>(model.predicate_count()), 0),
             padae::Load{}, Vector::Zero(n), model.analytic_jacobian()};
  m.load.df_dx.assign(static_cast<std::size_t>(model.pattern().nonzeros()), 0.0);
  m.load.dq_dx.assign(m.load.df_dx.size(), 0.0);
  // The charge matrix: semi-explicit systems have q_i = x_i on differential rows; others say
  // it through dq/dx (constant here).
  if (semi_explicit) {
    for (int i = 0; i < n; ++i)
      if (model.kind(i) == D) m.charge(i, i) = 1;
  } else {
    padae::Load load;
    load.f.setZero(n);
    load.q.setZero(n);
    load.df_dx.assign(m.load.df_dx.size(), 0.0);
    load.dq_dx.assign(m.load.df_dx.size(), 0.0);
    load.jacobian_requested = true;
    model.load(t0, x0, m.p, load);
    const auto& starts = model.pattern().column_starts();
    const auto& rows = model.pattern().row_indices();
    for (int column = 0; column < n; ++column)
      for (int k = starts[column]; k < starts[column + 1]; ++k) m.charge(rows[k], column) = load.dq_dx[k];
  }
  // Initial predicates from the guards (as padae::Integrator::initialize without p0).
  const int K = model.predicate_count();
  if (K > 0) {
    Vector g(K);
    model.guards(t0, x0, g);
    for (int k = 0; k < K; ++k) m.p[static_cast<std::size_t>(k)] = g[k] > 0;
  }

  SUNContext context;
  SUNContext_Create(nullptr, &context);
  N_Vector y = N_VNew_Serial(n, context), yp = N_VNew_Serial(n, context), id = N_VNew_Serial(n, context);
  for (int i = 0; i < n; ++i) {
    NV_Ith_S(y, i) = x0[i];
    NV_Ith_S(yp, i) = 0;
    NV_Ith_S(id, i) = model.kind(i) == A ? 0.0 : 1.0;
  }
  if (!semi_explicit) {
    const Vector rate = consistent_rate(m, t0, x0);
    for (int i = 0; i < n; ++i) NV_Ith_S(yp, i) = rate[i];
  }
  void* ida = IDACreate(context);
  SUNMatrix J = SUNDenseMatrix(n, n, context);
  SUNLinearSolver LS = SUNLinSol_Dense(y, J, context);
  auto fail = [&](const std::string& why) {
    run.ok = false;
    run.failure = why;
  };
  IDAInit(ida, ida_residual, t0, y, yp);
  IDASStolerances(ida, rtol, rtol);
  IDASetUserData(ida, &m);
  IDASetLinearSolver(ida, LS, J);
  if (m.analytic) IDASetJacFn(ida, ida_jacobian);
  // Algebraic unknowns (semi-explicit problems) are left out of the error test, as padae
  // tests the dynamic rows only. TRANSAMP has no purely algebraic unknown (its algebraic
  // equations mix node voltages that also carry charges), so IDA tests all eight there.
  IDASetId(ida, id);
  IDASetSuppressAlg(ida, SUNTRUE);
  IDASetMaxNumSteps(ida, kMaxIdaSteps);
  IDASetStopTime(ida, t_end);
  if (K > 0) {
    IDARootInit(ida, K, ida_roots);
    IDASetNoInactiveRootWarn(ida);
  }
  // IDAReInit resets IDA's counters: they are added up before each restart.
  auto add_counters = [&] {
    long steps = 0, iterations = 0, jacobians = 0, setups = 0, error_fails = 0, newton_fails = 0, residuals = 0;
    IDAGetNumSteps(ida, &steps);
    IDAGetNumNonlinSolvIters(ida, &iterations);
    IDAGetNumJacEvals(ida, &jacobians);
    IDAGetNumLinSolvSetups(ida, &setups);
    IDAGetNumErrTestFails(ida, &error_fails);
    IDAGetNumNonlinSolvConvFails(ida, &newton_fails);
    IDAGetNumResEvals(ida, &residuals);
    run.steps += steps;
    run.newton += iterations;
    run.jacobians += jacobians;
    run.factorizations += setups;
    run.rejected += error_fails + newton_fails;
    run.residuals += residuals;
  };
  const double span = t_end - t0;
  if (semi_explicit && IDACalcIC(ida, IDA_YA_YDP_INIT, t0 + 1e-3 * span) != IDA_SUCCESS) fail("IDACalcIC at t0");
  if (semi_explicit && run.ok) IDAGetConsistentIC(ida, y, yp);
  std::vector<int> roots(static_cast<std::size_t>(std::max(K, 1)));
  Vector g(K), g_ahead(K);
  double t = t0;
  while (run.ok && t < t_end) {
    const int flag = IDASolve(ida, t_end, &t, y, yp, IDA_NORMAL);
    if (flag == IDA_TSTOP_RETURN || (flag == IDA_SUCCESS && t >= t_end)) break;
    if (flag != IDA_ROOT_RETURN) {
      fail("IDASolve returned " + std::to_string(flag) + " at t = " + std::to_string(t));
      break;
    }
    IDAGetRootInfo(ida, roots.data());
    // A predicate flips in the direction its guard was heading (convention (9)); a guard that
    // returns to the side its predicate already says is no event.
    Vector e = Vector::Zero(K);
    int first = -1;
    for (int k = 0; k < K; ++k) {
      const int r = roots[static_cast<std::size_t>(k)];
      if (r != 0 && static_cast<bool>(m.p[static_cast<std::size_t>(k)]) != (r > 0)) {
        e[k] = r > 0 ? 1 : -1;
        if (first < 0) first = k;
      }
    }
    if (first < 0) continue;
    Event event;
    event.t = t;
    event.x_before.resize(n);
    Vector xdot(n), x(n);
    for (int i = 0; i < n; ++i) {
      event.x_before[i] = NV_Ith_S(y, i);
      xdot[i] = NV_Ith_S(yp, i);
    }
    if (semi_explicit)
      run.location_error = std::max(run.location_error, location_error(model, t, event.x_before, xdot, first));
    add_counters();
    // Jump x += X(t, x-, p-) e, flip, restart (IDAReInit + IDACalcIC), then the fixed point:
    // a guard with a definite sign against its predicate flips; a guard at zero (the one just
    // crossed, or one a jump left there) takes the side the new motion heads to, dg/dt along
    // the consistent y' (convention (9): an impact reverses the motion, the rod leaves the wall).
    int iteration = 0;
    for (; iteration < 50 && e.cwiseAbs().sum() > 0 && run.ok; ++iteration) {
      for (int i = 0; i < n; ++i) x[i] = NV_Ith_S(y, i);
      if (model.has_jumps()) {
        std::vector<padae::JumpEntry> entries;
        model.jump_matrix(t, x, m.p, entries);
        for (const auto& j : entries) x[j.row] += j.value * e[j.predicate];
      }
      for (int k = 0; k < K; ++k)
        if (e[k] != 0) m.p[static_cast<std::size_t>(k)] = e[k] > 0;
      for (int i = 0; i < n; ++i) NV_Ith_S(y, i) = x[i];
      IDAReInit(ida, t, y, yp);
      if (IDACalcIC(ida, IDA_YA_YDP_INIT, std::min(t_end, t + 1e-3 * span)) != IDA_SUCCESS) {
        fail("IDACalcIC after the event at t = " + std::to_string(t));
        break;
      }
      IDAGetConsistentIC(ida, y, yp);
      for (int i = 0; i < n; ++i) {
        x[i] = NV_Ith_S(y, i);
        xdot[i] = NV_Ith_S(yp, i);
      }
      const double dt = 1e-7 * std::max(std::abs(t), 1e-3);
      model.guards(t, x, g);
      model.guards(t + dt, x + dt * xdot, g_ahead);
      e.setZero();
      for (int k = 0; k < K; ++k) {
        const double tiny = 1e-9 * (1 + x.cwiseAbs().maxCoeff());
        const bool want = std::abs(g[k]) > tiny ? g[k] > 0 : g_ahead[k] > g[k];
        if (want != static_cast<bool>(m.p[static_cast<std::size_t>(k)])) e[k] = want ? 1 : -1;
      }
    }
    if (iteration == 50) fail("no predicate fixed point at t = " + std::to_string(t));
    event.x_after = x;
    run.events.push_back(event);
  }
  add_counters();
  run.x_end.resize(n);
  for (int i = 0; i < n; ++i) run.x_end[i] = NV_Ith_S(y, i);
  run.t_end = t;
  IDAFree(&ida);
  SUNLinSolFree(LS);
  SUNMatDestroy(J);
  N_VDestroy(y);
  N_VDestroy(yp);
  N_VDestroy(id);
  SUNContext_Free(&context);
  return run;
}

// --- problems -----------------------------------------------------------------------------------
struct Problem {
  std::string name, description;
  std::function<std::unique_ptr<padae::System>()> make;
  Vector x0;
  double t0 = 0, t_end = 1;
  bool semi_explicit = true;
  // The error measure (relative), and the event-time error (max |t - exact| / exact), of a run.
  std::function<double(const Run&)> error;
  std::function<double(const Run&)> event_error;
  std::function<int()> expected_events;
  // The tightest rtol of the sweep. The event-time target (1e-12 of the exact instant) needs
  // the integration's own error below it, so problems with events go down to 1e-15; TRANSAMP
  // stops at 1e-13, below which both solvers' steps fall to round-off.
  double tightest_rtol = 1e-13;
};

double rel(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

std::vector<Problem> problems() {
  std::vector<Problem> list;
  using padae::testing::Escapement;
  using padae::testing::EscapementModel;
  using padae::testing::PendulumClosedForm;
  using padae::testing::Masses;
  using padae::testing::MassesClosedForm;
  using padae::testing::Pendulum;
  using padae::testing::PendulumModel;
  {
    static const Masses m;
    static const MassesClosedForm exact(m);
    const double t_end = exact.t_contact + 0.9 * (exact.t_return - exact.t_contact);
    auto event_error = [](const Run& r) {
      double worst = 0;
      const double times[2] = {exact.t_capture, exact.t_contact};
      for (std::size_t i = 0; i < r.events.size() && i < 2; ++i) worst = std::max(worst, rel(r.events[i].t, times[i]));
      return r.events.size() == 2 ? worst : 1.0;
    };
    Problem p;
    p.name = "masses_jump";
    p.description = "paper (6): capture with a jump of v, then contact; x, v at the end against the closed form";
    p.make = [] { return std::make_unique<padae::testing::MassesWithJump>(m); };
    p.x0 = Vector{{0.0, 0.0, 0.0}};
    p.t_end = t_end;
    p.error = [t_end](const Run& r) {
      return std::max(std::abs(r.x_end[0] - exact.position(t_end)) / (1 + std::abs(exact.position(t_end))),
                      std::abs(r.x_end[1] - exact.velocity(t_end)) / (1 + std::abs(exact.velocity(t_end))));
    };
    p.event_error = event_error;
    p.expected_events = [] { return 2; };
    p.tightest_rtol = 1e-15;
    list.push_back(p);
    p.name = "masses_momentum";
    p.description = "paper (4): the same motion with the momentum as unknown, no jumps";
    p.make = [] { return std::make_unique<padae::testing::MassesMomentum>(m); };
    p.x0 = Vector{{0.0, 0.0}};
    p.error = [t_end](const Run& r) {
      const double v = r.x_end[1] / (m.m1 + m.m2);
      return std::max(std::abs(r.x_end[0] - exact.position(t_end)) / (1 + std::abs(exact.position(t_end))),
                      std::abs(v - exact.velocity(t_end)) / (1 + std::abs(exact.velocity(t_end))));
    };
    list.push_back(p);
  }
  {
    static const Escapement e;
    // Free damped oscillation from x = -0.5, v = 0: x = exp(-k t) (A cos wd t + B sin wd t).
    const double wd = std::sqrt(e.omega * e.omega - e.damping * e.damping);
    const double a0 = -0.5, b0 = e.damping * a0 / wd;
    // Upward zero: A cos + B sin = 0 with the derivative positive.
    double t1 = std::atan2(-a0, b0) / wd;
    while (t1 <= 0) t1 += std::numbers::pi / wd;
    auto xfree = [&](double t) { return std::exp(-e.damping * t) * (a0 * std::cos(wd * t) + b0 * std::sin(wd * t)); };
    auto vfree = [&](double t) {
      return std::exp(-e.damping * t) * ((-e.damping * a0 + wd * b0) * std::cos(wd * t) + (-e.damping * b0 - wd * a0) * std::sin(wd * t));
    };
    if (vfree(t1) < 0) t1 += std::numbers::pi / wd;
    (void)xfree;
    const double period = 2 * std::numbers::pi / wd, decay = std::exp(-e.damping * period);
    // Event k (0-based): upward at t1 + (k/2) T for even k, downward at t1 + T/2 + ((k-1)/2) T.
    static std::vector<double> times, kicks;
    times.clear();
    kicks.clear();
    const double t_end = t1 + 20.25 * period;
    double v_plus = vfree(t1) + e.kick;
    for (int k = 0; t1 + 0.5 * k * period < t_end; ++k) {
      times.push_back(t1 + 0.5 * k * period);
      if (k % 2 == 0) {
        kicks.push_back(v_plus);
        v_plus = v_plus * decay + e.kick;
      }
    }
    Problem p;
    p.name = "escapement";
    p.description = "paper (7): 21 kicks (upward zero crossings, jump of v) and 20 downward crossings; "
                    "event times and post-kick velocities against the closed form";
    p.make = [] { return std::make_unique<EscapementModel>(e); };
    p.x0 = Vector{{-0.5, 0.0, 0.0, 0.0}};
    p.t_end = t_end;
    p.error = [](const Run& r) {
      if (r.events.size() != times.size()) return 1.0;
      double worst = 0;
      for (std::size_t i = 0, kick = 0; i < r.events.size(); ++i) {
        worst = std::max(worst, rel(r.events[i].t, times[i]));
        if (i % 2 == 0) worst = std::max(worst, rel(r.events[i].x_after[1], kicks[kick++]));
      }
      return worst;
    };
    p.event_error = [](const Run& r) {
      if (r.events.size() != times.size()) return 1.0;
      double worst = 0;
      for (std::size_t i = 0; i < r.events.size(); ++i) worst = std::max(worst, rel(r.events[i].t, times[i]));
      return worst;
    };
    p.expected_events = [] { return static_cast<int>(times.size()); };
    p.tightest_rtol = 1e-15;
    list.push_back(p);
  }
  {
    static const Pendulum pendulum;
    const double phi0 = 0.1, omega0 = 0.5;
    const PendulumClosedForm closed_form{pendulum, phi0, omega0, 256};
    static std::vector<double> times, speeds;
    times.assign(1, closed_form.first_impact_time());
    speeds.assign(1, closed_form.first_impact_speed());
    for (int i = 1; i < 7; ++i) {
      times.push_back(times.back() + closed_form.flight(speeds.back()));
      speeds.push_back(pendulum.restitution * speeds.back());
    }
    const double t_end = 0.5 * (times[5] + times[6]);
    times.resize(6);
    speeds.resize(6);
    Problem p;
    p.name = "pendulum";
    p.description = "paper (10): 6 impacts on the wall (omega -> -k omega); impact times and speeds "
                    "against quadrature; stopped half-way to the 7th (the impacts accumulate at t = 0.97)";
    p.make = [] { return std::make_unique<PendulumModel>(pendulum); };
    p.x0 = Vector{{phi0, omega0}};
    p.t_end = t_end;
    p.error = [](const Run& r) {
      if (r.events.size() != times.size()) return 1.0;
      double worst = 0;
      for (std::size_t i = 0; i < times.size(); ++i)
        worst = std::max({worst, rel(r.events[i].t, times[i]), rel(r.events[i].x_before[1], speeds[i])});
      return worst;
    };
    p.event_error = [](const Run& r) {
      if (r.events.size() != times.size()) return 1.0;
      double worst = 0;
      for (std::size_t i = 0; i < times.size(); ++i) worst = std::max(worst, rel(r.events[i].t, times[i]));
      return worst;
    };
    p.expected_events = [] { return static_cast<int>(times.size()); };
    p.tightest_rtol = 1e-15;
    list.push_back(p);
  }
  {
    Problem p;
    p.name = "transistor_amp";
    p.description = "Bari test set TRANSAMP (index 1, 8 unknowns, stiff, smooth): error at t = 0.2 "
                    "against the published reference, max |y - ref| / (|ref| + 1)";
    p.make = [] { return std::make_unique<padae::testing::TransistorAmplifier>(); };
    p.x0 = padae::testing::TransistorAmplifier::initial_state();
    p.t_end = 0.2;
    p.semi_explicit = false;
    p.error = [](const Run& r) { return std::pow(10.0, -padae::testing::TransistorAmplifier::correct_digits(r.x_end)); };
    list.push_back(p);
  }
  return list;
}

void print_json_string(const std::string& s) {
  std::putchar('"');
  for (char c : s) {
    if (c == '"' || c == '\\') std::putchar('\\');
    if (static_cast<unsigned char>(c) < 0x20) {
      std::printf("\\u%04x", c);
      continue;
    }
    std::putchar(c);
  }
  std::putchar('"');
}

double finite_or(double x, double fallback) { return std::isfinite(x) ? x : fallback; }

}  // namespace

int main(int argc, char** argv) {
  // padae_ida_compare [min CPU seconds per configuration] [problem name]
  const double budget = argc > 1 ? std::atof(argv[1]) : 0.2;
  const std::string only = argc > 2 ? argv[2] : "";
  const std::vector<double> tolerances = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15};
  std::printf("{\"sundials\": \"%s\", \"problems\": [\n", SUNDIALS_VERSION);
  bool first_problem = true;
  for (const Problem& problem : problems()) {
    if (!only.empty() && problem.name != only) continue;
    std::printf("%s{\"name\": ", first_problem ? "" : ",\n");
    first_problem = false;
    print_json_string(problem.name);
    std::printf(", \"description\": ");
    print_json_string(problem.description);
    std::printf(", \"t_end\": %.17g, \"runs\": [\n", problem.t_end);
    bool first_run = true;
    for (const char* solver : {"padae", "ida"}) {
      for (double rtol : tolerances) {
        if (rtol < problem.tightest_rtol) continue;
        auto once = [&] {
          auto model = problem.make();
          return std::string(solver) == "padae"
                     ? run_padae(*model, problem.x0, problem.t0, problem.t_end, rtol, problem.semi_explicit)
                     : run_ida(*model, problem.x0, problem.t0, problem.t_end, rtol, problem.semi_explicit);
        };
        // CPU time: median over repetitions (the first included), at least 3 and at least
        // `budget` seconds in all.
        std::vector<double> times;
        double spent = 0;
        Run run;
        do {
          const double start = cpu_seconds();
          Run again = once();
          const double elapsed = cpu_seconds() - start;
          if (times.empty()) run = std::move(again);
          times.push_back(elapsed);
          spent += elapsed;
        } while (run.ok && (times.size() < 3 || (spent < budget && times.size() < 10000)));
        std::sort(times.begin(), times.end());
        if (std::getenv("IDA_COMPARE_EVENTS"))
          for (const Event& e : run.events) std::fprintf(stderr, "%s %g event t = %.12g x- = %.6g x+ = %.6g\n", solver, rtol, e.t, e.x_before[1], e.x_after[1]);
        const double cpu = times.empty() ? 0 : times[times.size() / 2];
        double error = 1, event_error = -1;
        int expected = problem.expected_events ? problem.expected_events() : 0;
        if (run.ok) {
          error = problem.error(run);
          if (problem.event_error) event_error = problem.event_error(run);
        }
        std::printf("%s {\"solver\": \"%s\", \"rtol\": %g, \"ok\": %s, \"failure\": ", first_run ? "" : ",\n", solver,
                    rtol, run.ok ? "true" : "false");
        first_run = false;
        print_json_string(run.failure);
        std::printf(", \"error\": %.6e, \"digits\": %.4f, \"cpu_s\": %.6e, \"repetitions\": %zu, \"steps\": %ld, "
                    "\"rejected\": %ld, \"newton_iterations\": %ld, \"jacobians\": %ld, \"factorizations\": %ld, "
                    "\"residuals\": %ld, \"events\": %zu, \"expected_events\": %d, \"event_time_error\": %.6e, "
                    "\"event_location_error\": %.6e}",
                    finite_or(error, 1.0), -std::log10(std::max(finite_or(error, 1.0), 1e-17)), cpu, times.size(),
                    run.steps, run.rejected, run.newton, run.jacobians, run.factorizations, run.residuals,
                    run.events.size(), expected, event_error, run.location_error);
        std::fflush(stdout);
      }
    }
    std::printf("\n]}");
  }
  std::printf("\n]}\n");
  return 0;
}
