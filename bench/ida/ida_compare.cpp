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
// IDA runs through ida_run.hpp: its dense linear solver (these systems have 2 to 8 unknowns;
// padae uses KLU), the charge matrix dq/dx constant in all these problems.
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

#include "ida_run.hpp"
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
Run run_ida(padae::System& model, const Vector& x0, double t0, double t_end, double rtol, bool semi_explicit) {
  Run run;
  const int n = model.size();
  // Initial predicates from the guards (as padae::Integrator::initialize without p0).
  const int K = model.predicate_count();
  Predicates p0(static_cast<std::size_t>(K), 0);
  if (K > 0) {
    Vector g(K);
    model.guards(t0, x0, g);
    for (int k = 0; k < K; ++k) p0[static_cast<std::size_t>(k)] = g[k] > 0;
  }
  ida_bench::IdaSettings settings;
  settings.rtol = rtol;
  settings.atol = Vector::Constant(n, rtol);
  settings.semi_explicit = semi_explicit;
  settings.max_steps = kMaxIdaSteps;
  // Algebraic unknowns (semi-explicit problems) are left out of the error test, as padae
  // tests the dynamic rows only. TRANSAMP has no purely algebraic unknown (its algebraic
  // equations mix node voltages that also carry charges), so IDA tests all eight there.
  settings.suppress_algebraic = true;
  ida_bench::IdaRun ida(model, t0, x0, p0, t_end - t0, settings);
  while (ida.ok() && ida.t() < t_end) {
    const ida_bench::Outcome outcome = ida.advance(t_end, t_end);
    if (outcome != ida_bench::Outcome::root) break;
    Event event;
    event.t = ida.t();
    event.x_before = ida.y();
    const Vector xdot = ida.yp();
    int first = -1;
    if (!ida.event(first)) continue;
    if (semi_explicit)
      run.location_error = std::max(run.location_error, location_error(model, event.t, event.x_before, xdot, first));
    event.x_after = ida.y();
    run.events.push_back(event);
  }
  if (!ida.ok()) {
    run.ok = false;
    run.failure = ida.failure();
  }
  const ida_bench::Counters c = ida.counters();
  run.steps = c.steps;
  run.rejected = c.rejected;
  run.newton = c.newton;
  run.jacobians = c.jacobians;
  run.factorizations = c.factorizations;
  run.residuals = c.residuals;
  run.x_end = ida.y();
  run.t_end = ida.t();
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
