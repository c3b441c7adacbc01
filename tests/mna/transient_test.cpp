// Transients through padae against closed forms: RC, RL, RLC responses, and the jumps of
// charge and flux at switching events with the energy they dissipate.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <tuple>
#include <algorithm>

#include "helpers.hpp"
#include "mna/start.hpp"
#include "mna/structure.hpp"

namespace mna::test {
namespace {

struct Simulation {
  bool ok = false;
  std::string failure;
  std::vector<double> times;
  std::vector<Vector> states;
  std::vector<padae::EventRecord> events;
  std::vector<double> dissipated;  // per event
  padae::Statistics statistics;
};

// A run to tstop, as the command makes it; `until` (when given) ends it early.
Simulation simulate(Model& model, double tstop, bool uic, double rtol = 1e-7,
                    Tolerances tolerances = {.voltage = 1e-9, .current = 1e-12}, double until = 0) {
  Simulation run;
  padae::Options options;
  options.rtol = rtol;
  options.time_scale = tstop;
  options.max_step = std::min(tstop / 50, model.resolution_step());  // as the command does
  options.peak_floor = 1e-3;                                          // as the command does
  model.set_tolerances(tolerances);
  if (until > 0) tstop = until;
  check_structure(model, uic ? StartKind::initial_conditions : StartKind::operating_point);
  Start start = find_start(model, 0, uic, options);
  if (!start.ok) {
    run.failure = start.message;
    return run;
  }
  padae::Integrator integrator(model, options);
  if (!integrator.initialize(0, start.x, start.p)) {
    run.failure = integrator.failure().reason;
    return run;
  }
  run.times.push_back(0), run.states.push_back(integrator.state());
  while (integrator.time() < tstop) {
    const padae::StepOutcome outcome = integrator.step(tstop);
    if (outcome.kind == padae::StepKind::failed) {
      run.failure = integrator.failure().reason;
      return run;
    }
    if (outcome.kind == padae::StepKind::event) {
      run.events.push_back(integrator.last_event());
      run.dissipated.push_back(model.jump_dissipation(integrator.last_event()));
    }
    run.times.push_back(integrator.time()), run.states.push_back(integrator.state());
  }
  run.statistics = integrator.statistics();
  run.ok = true;
  return run;
}

// A control voltage ramping linearly from `from` to `to` over 2 ms: it crosses 0.5 at 1 ms.
void ramp_control(CircuitSpec& c, double from, double to) {
  c.add("vctl", {"ctl", "0"}).waveform = {Waveform::Shape::piecewise_linear, {0, from, 2e-3, to}};
}
ElementSpec& ideal_switch(CircuitSpec& c, const std::string& name, const std::string& a, const std::string& b, bool on = false) {
  auto& s = c.add(name, {a, b, "ctl", "0"});
  s.model = {{"vt", 0.5}, {"vh", 0.0}, {"ron", 0.0}, {"roff", infinity}};
  s.initially_on = on;
  return s;
}

TEST(Transient, RcChargingFollowsExponential) {
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 1.0);
  c.add("r1", {"in", "out"}, 1e3);
  c.add("c1", {"out", "0"}, 1e-6).initial_condition = 0.0;
  Model m(c, {.tstep = 1e-5, .tstop = 5e-3});
  const Simulation run = simulate(m, 5e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  const int out = unknown(m, "v(out)");
  for (std::size_t k = 0; k < run.times.size(); ++k)
    EXPECT_NEAR(run.states[k][out], 1 - std::exp(-run.times[k] / 1e-3), 2e-5) << "t = " << run.times[k];
  EXPECT_LT(run.times.size(), 400u);  // variable order BDF takes large steps
}

TEST(Transient, RlCurrentRisesToVOverR) {
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 2.0);
  c.add("r1", {"in", "a"}, 4.0);
  c.add("l1", {"a", "0"}, 8e-3).initial_condition = 0.0;
  Model m(c, {.tstep = 1e-5, .tstop = 10e-3});
  const Simulation run = simulate(m, 10e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  const int i = unknown(m, "i(l1)");
  for (std::size_t k = 0; k < run.times.size(); ++k)
    EXPECT_NEAR(run.states[k][i], 0.5 * (1 - std::exp(-run.times[k] * 4 / 8e-3)), 1e-5) << "t = " << run.times[k];
}

TEST(Transient, SeriesRlcRingsDown) {
  // Capacitor at 1 V discharging through R and L: i(t) = -(V0 / (w L)) e^(-a t) sin(w t).
  const double r = 10, l = 1e-3, cap = 1e-6, v0 = 1;
  CircuitSpec c;
  c.add("c1", {"a", "0"}, cap).initial_condition = v0;
  c.add("r1", {"a", "b"}, r);
  c.add("l1", {"b", "0"}, l).initial_condition = 0.0;
  Model m(c, {.tstep = 1e-6, .tstop = 1e-3});
  const Simulation run = simulate(m, 1e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  const double alpha = r / (2 * l), w = std::sqrt(1 / (l * cap) - alpha * alpha);
  const int i = unknown(m, "i(l1)");
  for (std::size_t k = 0; k < run.times.size(); ++k) {
    const double t = run.times[k];
    EXPECT_NEAR(run.states[k][i], v0 / (w * l) * std::exp(-alpha * t) * std::sin(w * t), 1e-5) << "t = " << t;
  }
}

TEST(Start, FloatingCapacitorRunFarShorterThanItsTimeConstant) {
  // V1 - R1 - C1 - R2 - ground with uic, simulated for 1e-3 of RC: the capacitor has no DC path
  // of its own, so C/h of a vanishing step swamps the conductances in double precision. The
  // node voltages still follow i = V/(R1+R2) e^(-t/((R1+R2)C)) from the consistent start.
  const double r = 1e3, cap = 1e-6, tstop = 1e-6;
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 1.0);
  c.add("r1", {"in", "a"}, r);
  c.add("c1", {"a", "b"}, cap).initial_condition = 0.0;
  c.add("r2", {"b", "0"}, r);
  Model m(c, {.tstep = 2e-8, .tstop = tstop});
  const Simulation run = simulate(m, tstop, true);
  ASSERT_TRUE(run.ok) << run.failure;
  const int a = unknown(m, "v(a)"), b = unknown(m, "v(b)");
  for (std::size_t k = 0; k < run.times.size(); ++k) {
    const double current = 1 / (2 * r) * std::exp(-run.times[k] / (2 * r * cap));
    EXPECT_NEAR(run.states[k][a], 1 - r * current, 1e-9) << "t = " << run.times[k];
    EXPECT_NEAR(run.states[k][b], r * current, 1e-9) << "t = " << run.times[k];
  }
}

TEST(Jump, TwoCapacitorsShareCharge) {
  const double c1 = 1e-6, c2 = 2e-6, v1 = 5, v2 = 1;
  CircuitSpec c;
  ramp_control(c, 0, 1);
  c.add("c1", {"a", "0"}, c1).initial_condition = v1;
  c.add("c2", {"b", "0"}, c2).initial_condition = v2;
  ideal_switch(c, "s1", "a", "b");
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 1u);
  const auto& event = run.events[0];
  EXPECT_NEAR(event.t, 1e-3, 1e-12);
  EXPECT_TRUE(event.jumped);
  const double shared = (c1 * v1 + c2 * v2) / (c1 + c2);
  const int a = unknown(m, "v(a)"), b = unknown(m, "v(b)");
  EXPECT_NEAR(event.x_before[a], v1, 1e-12);
  EXPECT_NEAR(event.x_after[a], shared, 1e-12 * shared);
  EXPECT_NEAR(event.x_after[b], shared, 1e-12 * shared);
  EXPECT_NEAR(run.states.back()[a], shared, 1e-12 * shared);
  const double lost = 0.5 * c1 * c2 / (c1 + c2) * (v1 - v2) * (v1 - v2);
  EXPECT_NEAR(run.dissipated[0], lost, 1e-9 * lost);
  // The switch carried the charge that moved: C2 (shared - V2).
  EXPECT_NEAR(std::abs(event.impulse[unknown(m, "i(s1)")]), c2 * (shared - v2), 1e-12 * c2 * shared);
}

TEST(Jump, CapacitorSwitchedOntoVoltageSource) {
  const double cap = 1e-6, vs = 10, v0 = 2;
  CircuitSpec c;
  ramp_control(c, 0, 1);
  c.add("v1", {"s", "0"}, vs);
  c.add("c1", {"a", "0"}, cap).initial_condition = v0;
  ideal_switch(c, "s1", "s", "a");
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 1u);
  const int a = unknown(m, "v(a)");
  EXPECT_NEAR(run.events[0].x_after[a], vs, 1e-12 * vs);
  // The source delivers C (Vs - V0) Vs; the capacitor keeps half of what it gains.
  const double lost = 0.5 * cap * (vs - v0) * (vs - v0);
  EXPECT_NEAR(run.dissipated[0], lost, 1e-9 * lost);
}

TEST(Jump, ThreeCapacitorsTwoSwitchesClosingAtOnce) {
  const double cs[] = {1e-6, 2e-6, 3e-6}, vs[] = {6, -1, 2};
  CircuitSpec c;
  ramp_control(c, 0, 1);
  const char* nodes[] = {"a", "b", "d"};
  for (int k = 0; k < 3; ++k) c.add(std::string("c").append(std::to_string(k + 1)), {nodes[k], "0"}, cs[k]).initial_condition = vs[k];
  ideal_switch(c, "s1", "a", "b");
  ideal_switch(c, "s2", "b", "d");
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 1u);  // both predicates flip in one event
  EXPECT_EQ(run.events[0].flips.size(), 2u);
  double charge = 0, capacitance = 0, before = 0;
  for (int k = 0; k < 3; ++k) charge += cs[k] * vs[k], capacitance += cs[k], before += 0.5 * cs[k] * vs[k] * vs[k];
  const double shared = charge / capacitance;
  for (const char* n : nodes) EXPECT_NEAR(run.events[0].x_after[unknown(m, std::string("v(") + n + ")")], shared, 1e-12 * std::abs(shared));
  const double lost = before - 0.5 * capacitance * shared * shared;
  EXPECT_NEAR(run.dissipated[0], lost, 1e-9 * lost);
}

TEST(Jump, SeriesCapacitorsChargeTogether) {
  // A source switched onto C1 in series with C2: the same charge Q = Ceq Vs lands on both.
  const double c1 = 1e-6, c2 = 3e-6, vs = 8;
  CircuitSpec c;
  ramp_control(c, 0, 1);
  c.add("v1", {"s", "0"}, vs);
  c.add("c1", {"a", "m"}, c1).initial_condition = 0.0;
  c.add("c2", {"m", "0"}, c2).initial_condition = 0.0;
  ideal_switch(c, "s1", "s", "a");
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 1u);
  const double ceq = c1 * c2 / (c1 + c2), q = ceq * vs;
  const auto& after = run.events[0].x_after;
  EXPECT_NEAR(after[unknown(m, "v(a)")], vs, 1e-12 * vs);
  EXPECT_NEAR(after[unknown(m, "v(m)")], q / c2, 1e-12 * vs);
  const double lost = 0.5 * ceq * vs * vs;
  EXPECT_NEAR(run.dissipated[0], lost, 1e-9 * lost);
}

TEST(Jump, OpeningSwitchPutsInductorsInSeriesConservingFlux) {
  // L1 carries I0 around a loop closed by a switch across L2; opening it leaves L1 and L2 in
  // series: flux is conserved, L1 I0 = (L1 + L2) I, and the difference in energy is lost.
  const double l1 = 2e-3, l2 = 3e-3, i0 = 1.5, r = 1e-3;
  CircuitSpec c;
  ramp_control(c, 1, 0);
  c.add("l1", {"a", "b"}, l1).initial_condition = i0;
  c.add("l2", {"b", "0"}, l2).initial_condition = 0.0;
  c.add("r1", {"0", "a"}, r);
  ideal_switch(c, "s1", "b", "0", true);
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 1u);
  const int i1 = unknown(m, "i(l1)"), i2 = unknown(m, "i(l2)");
  const auto& event = run.events[0];
  const double before = event.x_before[i1];
  EXPECT_NEAR(before, i0 * std::exp(-r / l1 * 1e-3), 1e-6 * i0);  // decayed through R before
  const double after = l1 * before / (l1 + l2);
  EXPECT_NEAR(event.x_after[i1], after, 1e-12 * i0);
  EXPECT_NEAR(event.x_after[i2], after, 1e-12 * i0);
  const double lost = 0.5 * l1 * before * before - 0.5 * (l1 + l2) * after * after;
  EXPECT_NEAR(run.dissipated[0], lost, 1e-9 * lost);
}

TEST(Jump, InductorFreewheelsThroughIdealDiodeWhenSwitchOpens) {
  // V charges L through R while the switch is on; when it opens the current moves to the
  // freewheeling diode without a jump, then decays with L/R.
  const double vs = 10, r = 5, l = 10e-3;
  CircuitSpec c;
  ramp_control(c, 1, 0);
  c.add("v1", {"s", "0"}, vs);
  ideal_switch(c, "s1", "s", "a", true);
  // Both ideal (ROFF infinite): opening the switch alone would break the inductor current with
  // an impulse of voltage at a, which is what turns the diode on in the same event.
  c.add("d1", {"0", "a"}).model = {{"ideal", 1}};
  c.add("l1", {"a", "b"}, l).initial_condition = 0.0;
  c.add("r1", {"b", "0"}, r);
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_GE(run.events.size(), 1u);
  const int i = unknown(m, "i(l1)"), a = unknown(m, "v(a)"), id = unknown(m, "i(d1)");
  const double tau = l / r, i1 = vs / r * (1 - std::exp(-1e-3 / tau));
  const auto& event = run.events[0];
  EXPECT_NEAR(event.t, 1e-3, 1e-12);
  EXPECT_NEAR(event.x_after[i], i1, 1e-6 * i1);   // no flux jump: the diode takes the current
  EXPECT_NEAR(event.x_after[id], i1, 1e-6 * i1);
  EXPECT_NEAR(event.x_after[a], 0, 1e-9);
  EXPECT_NEAR(run.dissipated[0], 0, 1e-12);
  EXPECT_NEAR(run.states.back()[i], i1 * std::exp(-1e-3 / tau), 1e-5 * i1);
}

TEST(Jump, IdealSwitchClosingAcrossAConductingIdealDiodeTurnsItOff) {
  // 1 mA flows into a and down through an ideal diode (no forward voltage, no resistance). At
  // 1 ms (the control ramp crossing 0.5 V) an ideal switch closes across it: with both on the
  // current's split is undetermined; with the diode off the switch carries it, a stays at 0 V
  // and the diode's guard (its voltage, 0) keeps it off: the synchronous rectifier's switch
  // turning on while its body diode freewheels.
  CircuitSpec c;
  ramp_control(c, 0, 1);
  c.add("i1", {"0", "a"}, 1e-3);
  c.add("r1", {"a", "0"}, 1e6);  // the operating point's path before the diode is found on
  c.add("d1", {"a", "0"}).model = {{"ideal", 1}};
  ideal_switch(c, "s1", "a", "0");
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, false);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 1u);
  EXPECT_NEAR(run.events[0].t, 1e-3, 1e-12);
  const int is = unknown(m, "i(s1)"), id = unknown(m, "i(d1)"), a = unknown(m, "v(a)");
  EXPECT_NEAR(run.events[0].x_before[id], 1e-3, 1e-12);
  EXPECT_NEAR(run.states.back()[is], 1e-3, 1e-12);
  EXPECT_NEAR(run.states.back()[id], 0, 1e-12);
  EXPECT_NEAR(run.states.back()[a], 0, 1e-12);
}

TEST(Jump, FullBridgeDiagonalSwitchesCloseAcrossTwoFreewheelingDiodes) {
  // A full-bridge inverter with an RL load, ideal switches and antiparallel ideal diodes (all
  // without resistance). S1 and S4 conduct until 500.5 us; in the 10 us dead time D2 and D3
  // carry the load current back to the supply; at 510.5 us S2 and S3 close across them together:
  // each pair's current split is undetermined with both on, so both diodes turn off. v(a, b)
  // is +-100 V from each switch-off (the diodes take over at once), and i(L) follows the
  // exponentials towards +-10 A with tau = L / R = 1 ms.
  const double vdc = 100, r = 10, l = 10e-3;
  CircuitSpec c;
  c.add("vdc", {"p", "0"}, vdc);
  c.add("vg1", {"g1", "0"}).waveform = {Waveform::Shape::pulse, {0, 5, 10e-6, 1e-6, 1e-6, 489e-6, 1e-3}};
  c.add("vg2", {"g2", "0"}).waveform = {Waveform::Shape::pulse, {0, 5, 510e-6, 1e-6, 1e-6, 489e-6, 1e-3}};
  for (auto [name, a, b, gate] : {std::tuple{"s1", "p", "a", "g1"}, {"s4", "b", "0", "g1"}, {"s2", "a", "0", "g2"}, {"s3", "p", "b", "g2"}}) {
    auto& s = c.add(name, {a, b, gate, "0"});
    s.model = {{"vt", 2.5}, {"vh", 0.0}, {"ron", 0.0}, {"roff", infinity}};
  }
  for (auto [name, anode, cathode] : {std::tuple{"d1", "a", "p"}, {"d2", "0", "a"}, {"d3", "b", "p"}, {"d4", "0", "b"}})
    c.add(name, {anode, cathode}).model = {{"ideal", 1}};
  c.add("r1", {"a", "x"}, r);
  c.add("l1", {"x", "b"}, l);
  c.add("rbias", {"a", "0"}, 1e9);  // the operating point's voltages with every switch open
  c.add("rbias2", {"b", "0"}, 1e9);
  Model m(c, {.tstep = 1e-6, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, false);
  ASSERT_TRUE(run.ok) << run.failure;
  auto current = [&](double t) {
    if (t < 10.5e-6) return 0.0;
    double i = 0, from = 10.5e-6, v = vdc;
    for (double edge = 500.5e-6;; edge += 500e-6, v = -v) {
      const double to = std::min(edge, t);
      i = v / r + (i - v / r) * std::exp(-(to - from) * r / l);
      from = to;
      if (edge >= t) return i;
    }
  };
  const int il = unknown(m, "i(l1)");
  for (std::size_t k = 0; k < run.times.size(); ++k) EXPECT_NEAR(run.states[k][il], current(run.times[k]), 1e-5) << run.times[k];
  const auto closing = std::find_if(run.events.begin(), run.events.end(), [](const auto& e) { return std::abs(e.t - 510.5e-6) < 1e-9; });
  ASSERT_NE(closing, run.events.end());
  for (const char* diode : {"i(d2)", "i(d3)"}) EXPECT_NEAR(closing->x_after[unknown(m, diode)], 0, 1e-9) << diode;
  EXPECT_NEAR(closing->x_after[unknown(m, "i(s2)")], -current(510.5e-6), 1e-5);
}

TEST(Jump, BuckBoostDiodeTurnOffLeavesTheSwitchNodeAtZero) {
  // An inverting buck-boost (ideal switch and diode, ROFF 1e12) in discontinuous conduction:
  // when D1's current reaches zero, L1 holds no current and no voltage, so v(sw) = 0 until the
  // switch closes. The event leaves picoamperes in L1, which ROFF drains in 1e-17 s: a fast mode
  // that moves less charge than a step's error. It must neither be integrated with the
  // trapezoidal rule (v(sw) swung -18 V -> +18 V) nor shift the rows.
  CircuitSpec c;
  c.add("vin", {"in", "0"}, 20.0);
  c.add("vg", {"g", "0"}).waveform = {Waveform::Shape::pulse, {0, 5, 0, 20e-9, 20e-9, 6e-6, 20e-6}};
  auto& s1 = c.add("s1", {"in", "sw", "g", "0"});
  s1.model = {{"vt", 2.5}, {"vh", 0.0}, {"ron", 0.0}, {"roff", 1e12}};
  c.add("l1", {"sw", "0"}, 20e-6);
  c.add("d1", {"out", "sw"}).model = {{"ideal", 1}, {"roff", 1e12}};
  c.add("c1", {"out", "0"}, 22e-6);
  c.add("rl", {"out", "0"}, 20.0);
  Model m(c, {.tstep = 20e-9, .tstop = 1e-3});
  const Simulation run = simulate(m, 1e-3, false, 1e-3);
  ASSERT_TRUE(run.ok) << run.failure;
  const int sw = unknown(m, "v(sw)"), out = unknown(m, "v(out)");
  // D1 turning off by itself (not as the switch closes, in continuous conduction).
  auto flips = [&](const padae::EventRecord& event, const std::string& element) {
    return std::any_of(event.flips.begin(), event.flips.end(),
                       [&](const auto& f) { return m.predicate_owner(f.predicate).name() == element; });
  };
  int turn_offs = 0;
  for (const auto& event : run.events)
    if (flips(event, "d1") && !flips(event, "s1")) {
      ++turn_offs;
      EXPECT_NEAR(event.x_after[sw], 0, 1e-3) << "t = " << event.t;
    }
  EXPECT_GE(turn_offs, 20);
  // Between a turn-off and the switch closing, the rows are at 0 V too; v(sw) never leaves
  // [v(out), vin].
  for (std::size_t k = 0; k < run.times.size(); ++k) {
    EXPECT_LE(run.states[k][sw], 20 + 1e-6) << "t = " << run.times[k];
    EXPECT_GE(run.states[k][sw], run.states[k][out] - 1e-6) << "t = " << run.times[k];
  }
}

TEST(Jump, IdealFlybackInDiscontinuousConductionKeepsItsEnergyBalanceAtLooseTolerance) {
  // A flyback with perfect coupling, ideal switch and diode, in discontinuous conduction: each
  // period stores Lp Ipk^2 / 2 (Ipk = Vin Ton / Lp) and delivers all of it to the load, so in
  // steady state Vo = Vin Ton sqrt(R f / (2 Lp)). Ton = 4.001 us: the gate crosses vt halfway
  // through its 1 ns edges. Each period's charge reaches C1 in 3 us of linearly falling diode
  // current, which a backward-Euler step under-delivers by a fixed share every period: at rtol
  // 1e-3 the output used to settle 13.6 % low.
  const double vin = 12, ton = 4.001e-6, period = 20e-6, lp = 100e-6, r = 100;
  CircuitSpec c;
  c.add("vin", {"in", "0"}, vin);
  c.add("vg", {"g", "0"}).waveform = {Waveform::Shape::pulse, {0, 5, 0, 1e-9, 1e-9, 4e-6, period}};
  c.add("lp", {"in", "drain"}, lp);
  c.add("ls", {"0", "sec"}, lp / 4);
  c.add("k1", {}, 1.0).controls = {"lp", "ls"};
  auto& s1 = c.add("s1", {"drain", "0", "g", "0"});
  s1.model = {{"vt", 2.5}, {"vh", 0.0}, {"ron", 0.0}, {"roff", 1e12}};
  c.add("d1", {"sec", "out"}).model = {{"ideal", 1}, {"ron", 0.0}, {"roff", 1e12}, {"vfwd", 0.0}};
  c.add("c1", {"out", "0"}, 100e-6);
  c.add("rl", {"out", "0"}, r);
  Model m(c, {.tstep = 1e-6, .tstop = 60e-3});
  const Simulation run = simulate(m, 60e-3, true, 1e-3);
  ASSERT_TRUE(run.ok) << run.failure;
  // Mean of v(out) over the last 10 ms (500 periods; the output's time constant is 5 ms).
  const int out = unknown(m, "v(out)");
  double area = 0;
  for (std::size_t k = 1; k < run.times.size(); ++k)
    if (run.times[k - 1] >= 50e-3)
      area += (run.times[k] - run.times[k - 1]) * (run.states[k][out] + run.states[k - 1][out]) / 2;
  const double expected = vin * ton * std::sqrt(r / (2 * lp * period));
  EXPECT_NEAR(area / 10e-3, expected, 2e-3 * expected);
}

TEST(Events, IdealDiodeClampConductsAtEveryPeakOfTheSine) {
  // A DC restorer: C couples a 5 V, 10 kHz sine to out, an ideal diode (VFWD 0.3) clamps out at
  // 0.3 V, RL loads out (tau = RL C = 0.1 s). The diode conducts from where out reaches 0.3 V
  // until the peak, a window of 0.7 us of each 100 us period: shorter than the steps the
  // sine allows (5 us). It turns off at each peak with its current and its voltage at their
  // thresholds together. Closed form between: C's voltage u obeys u' = (v(in) - u) / tau from
  // 5 - 0.3 V at the peak; the diode turns on where v(in) - u = 0.3.
  const double amplitude = 5, frequency = 1e4, vfwd = 0.3, tau = 0.1;
  CircuitSpec c;
  c.add("v1", {"in", "0"}).waveform = {Waveform::Shape::sine, {0, amplitude, frequency}};
  c.add("c1", {"in", "out"}, 1e-6);
  c.add("d1", {"out", "0"}).model = {{"ideal", 1}, {"vfwd", vfwd}};
  c.add("rl", {"out", "0"}, 1e5);
  const double tstop = 2e-3;
  Model m(c, {.tstep = 1e-7, .tstop = tstop});
  const Simulation run = simulate(m, tstop, false, 1e-6);
  ASSERT_TRUE(run.ok) << run.failure;
  const double w = 2 * std::numbers::pi * frequency, period = 1 / frequency;
  ASSERT_EQ(run.events.size(), 2 * 20u);
  for (int k = 1; k < 20; ++k) {
    const double peak = 0.25 * period + (k - 1) * period, next_peak = peak + period;
    // u = u_p + (u(peak) - u_p(peak)) exp(-(t - peak) / tau), u_p the sine's periodic response.
    auto periodic = [&](double t) {
      return amplitude * (std::sin(w * t) - w * tau * std::cos(w * t)) / (1 + w * w * tau * tau);
    };
    auto excess = [&](double t) {
      const double u = periodic(t) + (amplitude - vfwd - periodic(peak)) * std::exp(-(t - peak) / tau);
      return amplitude * std::sin(w * t) - u - vfwd;
    };
    double lo = next_peak - 0.25 * period, hi = next_peak;  // excess < 0 at lo, > 0 at hi
    for (int i = 0; i < 100; ++i) (excess(0.5 * (lo + hi)) > 0 ? hi : lo) = 0.5 * (lo + hi);
    // out's error, some 10 rtol of 5 V, over its slope there, 1.4e4 V/s: 4 ns.
    EXPECT_NEAR(run.events[2 * k].t, lo, 1e-8) << "turn-on " << k;
    EXPECT_NEAR(run.events[2 * k + 1].t, next_peak, 1e-9) << "turn-off " << k;
  }
}

TEST(Start, OperatingPointSetsCapacitorToDividerVoltage) {
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 3.0);
  c.add("r1", {"in", "out"}, 2e3);
  c.add("r2", {"out", "0"}, 1e3);
  c.add("c1", {"out", "0"}, 1e-6);
  Model m(c, {.tstep = 1e-5, .tstop = 1e-3});
  const Simulation run = simulate(m, 1e-3, false);
  ASSERT_TRUE(run.ok) << run.failure;
  for (const auto& x : run.states) EXPECT_NEAR(x[unknown(m, "v(out)")], 1.0, 1e-9);
}

// A single-phase bridge of ideal diodes fed through Ls from a sine at its peak, loaded by a
// constant current Id (the textbook rectifier with a smoothing inductor). Its operating point has
// D1 and D4 conducting: with all four off the current source has no path, with all four on they
// short the source. At the source's zero (5 ms) the commutation overlap begins: the source is
// shorted through Ls and i(Ls) swings from Id to -Id in u / w, where 1 - cos u = 2 w Ls Id / Vm.
// From initial conditions instead (uic, IC = Id on Ls), all four diodes turn on at the start
// (their voltages are 0 and the inductor drives them): that mode leaves the current around the
// diodes' loop undetermined, and one of them turns off.
void expect_bridge_commutates_as_closed_form(double off_resistance, bool uic = false) {
  const double vm = 100, w = 2 * std::numbers::pi * 50, ls = 5e-3, id = 10;
  CircuitSpec c;
  c.add("vs", {"s", "0"}).waveform = {Waveform::Shape::sine, {0, vm, 50, 0, 0, 90}};
  c.add("ls", {"s", "a"}, ls).initial_condition = id;
  for (auto [name, anode, cathode] : {std::tuple{"d1", "a", "p"}, {"d2", "0", "p"}, {"d3", "n", "a"}, {"d4", "n", "0"}})
    c.add(name, {anode, cathode}).model = {{"ideal", 1}, {"roff", off_resistance}};
  c.add("iload", {"p", "n"}, id);
  Model m(c, {.tstep = 1e-5, .tstop = 10e-3});
  const Simulation run = simulate(m, 10e-3, uic, 1e-8);
  ASSERT_TRUE(run.ok) << run.failure;
  const int il = unknown(m, "i(ls)"), p = unknown(m, "v(p)"), n = unknown(m, "v(n)");
  EXPECT_NEAR(run.states[0][il], id, 1e-6);
  // Before the overlap and after it, the bridge puts |v(s)| across the load: Vm at 0 and 10 ms.
  if (!uic) {
    EXPECT_NEAR(run.states[0][p] - run.states[0][n], vm, 1e-6);
  }
  EXPECT_NEAR(run.states.back()[p] - run.states.back()[n], vm, 1e-6);
  const double overlap_end = 5e-3 + std::acos(1 - 2 * w * ls * id / vm) / w;
  const auto last = std::find_if(run.events.rbegin(), run.events.rend(), [](const auto& e) { return e.t < 9e-3; });
  ASSERT_NE(last, run.events.rend());
  EXPECT_NEAR(last->t, overlap_end, 1e-9);
  EXPECT_NEAR(run.states.back()[il], -id, 1e-6);
}

TEST(Start, IdealDiodeBridgeUnderACurrentSourceFindsItsConductingPair) {
  expect_bridge_commutates_as_closed_form(infinity);
}

TEST(Start, IdealDiodeBridgeWithOffResistanceFindsItsConductingPair) {
  expect_bridge_commutates_as_closed_form(1e9);
}

TEST(Start, IdealDiodeBridgeFromInitialConditionsTurnsOneOfItsLoopOff) {
  expect_bridge_commutates_as_closed_form(1e9, true);
}

TEST(Start, IdealDiodeBridgeFromRestTurnsOnTheCurrentSourcesDiodes) {
  // The bridge from rest (uic, i(Ls) = 0) with the source at its zero: with every diode off the
  // current source has no path. All four conduct (the source shorted through Ls, the load's
  // current split between the legs) until i(Ls) = (Vm / (w Ls)) (1 - cos w t) reaches Id, when
  // D3 turns off.
  const double vm = 100, w = 2 * std::numbers::pi * 50, ls = 5e-3, id = 10;
  CircuitSpec c;
  c.add("vs", {"s", "0"}).waveform = {Waveform::Shape::sine, {0, vm, 50}};
  c.add("ls", {"s", "a"}, ls);
  for (auto [name, anode, cathode] : {std::tuple{"d1", "a", "p"}, {"d2", "0", "p"}, {"d3", "n", "a"}, {"d4", "n", "0"}})
    c.add(name, {anode, cathode}).model = {{"ideal", 1}};
  c.add("iload", {"p", "n"}, id);
  Model m(c, {.tstep = 1e-5, .tstop = 4e-3});
  const Simulation run = simulate(m, 4e-3, true, 1e-8);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_FALSE(run.events.empty());
  const double t_full = std::acos(1 - id * w * ls / vm) / w;
  EXPECT_NEAR(run.events[0].t, t_full, 1e-9);
  EXPECT_NEAR(run.events[0].x_after[unknown(m, "i(ls)")], id, 1e-6);
  EXPECT_NEAR(run.events[0].x_after[unknown(m, "i(d3)")], 0, 1e-6);
}

// Two capacitors in series with their own IC= (C2 0.5 V from b to m, C3 1.5 V from m to ground)
// are two states: v(b) = 2 V, v(m) = 1.5 V at the start, whatever the cards' order or whether m's
// 1.5 V comes from C3's IC= or from .ic. Through R (1 kOhm from b to ground) both lose the same
// charge: v(b) = 2 exp(-t / RC'), C' = C / 2, and v(m) = 1.5 - (2 - v(b)) / 2. (A capacitor's
// voltage was written into its node from the other node's value when its card came: C2 before
// C3 started at v(b) = 0.5 V.)
TEST(Start, SeriesCapacitorsInitialVoltagesHoldInAnyCardOrder) {
  for (const int variant : {0, 1, 2}) {
    CircuitSpec c;
    c.add("r1", {"b", "0"}, 1e3);
    if (variant == 1) c.add("c3", {"m", "0"}, 1e-9).initial_condition = 1.5;
    c.add("c2", {"b", "m"}, 1e-9).initial_condition = 0.5;
    if (variant == 0) c.add("c3", {"m", "0"}, 1e-9).initial_condition = 1.5;
    if (variant == 2) c.add("c3", {"m", "0"}, 1e-9), c.initial_voltages["m"] = 1.5;
    Model m(c, {.tstep = 1e-8, .tstop = 3e-6});
    const Simulation run = simulate(m, 3e-6, true);
    ASSERT_TRUE(run.ok) << run.failure;
    const int b = unknown(m, "v(b)"), mid = unknown(m, "v(m)");
    EXPECT_DOUBLE_EQ(run.states.front()[b], 2.0) << variant;
    EXPECT_DOUBLE_EQ(run.states.front()[mid], 1.5) << variant;
    for (std::size_t k = 0; k < run.times.size(); ++k) {
      const double v_b = 2 * std::exp(-run.times[k] / 0.5e-6);
      EXPECT_NEAR(run.states[k][b], v_b, 2e-5) << variant << " at " << run.times[k];
      EXPECT_NEAR(run.states[k][mid], 1.5 - (2 - v_b) / 2, 2e-5) << variant << " at " << run.times[k];
    }
  }
}

// A device's IC= overrides .ic on the same node (SPICE's precedence), and of two IC= that
// cannot both hold the first card's is kept; a capacitor between two otherwise free nodes
// keeps its voltage too.
TEST(Start, DeviceInitialConditionsOverrideDotIcAndTheFirstOfAConflictIsKept) {
  CircuitSpec c;
  c.add("r1", {"a", "0"}, 1e3);
  c.add("c1", {"a", "0"}, 1e-9).initial_condition = 1.0;
  c.add("c2", {"a", "0"}, 1e-9).initial_condition = 3.0;
  c.initial_voltages["a"] = 2.0;
  c.add("r2", {"p", "q"}, 1e3);
  c.add("c3", {"p", "q"}, 1e-9).initial_condition = 0.7;
  Model m(c, {.tstep = 1e-8, .tstop = 1e-6});
  const Vector x0 = m.initial_conditions();
  EXPECT_DOUBLE_EQ(x0[unknown(m, "v(a)")], 1.0);
  EXPECT_DOUBLE_EQ(x0[unknown(m, "v(p)")] - x0[unknown(m, "v(q)")], 0.7);
}

TEST(Start, HeldInitialVoltageThenRelaxes) {
  // .ic v(out)=2 without uic: the op holds it, then the capacitor relaxes toward 1 V with
  // tau = (R1 || R2) C.
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 2.0);
  c.add("r1", {"in", "out"}, 1e3);
  c.add("r2", {"out", "0"}, 1e3);
  c.add("c1", {"out", "0"}, 1e-6);
  c.initial_voltages["out"] = 2.0;
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, false);
  ASSERT_TRUE(run.ok) << run.failure;
  const int out = unknown(m, "v(out)");
  for (std::size_t k = 0; k < run.times.size(); ++k)
    EXPECT_NEAR(run.states[k][out], 1 + std::exp(-run.times[k] / 0.5e-3), 2e-5) << run.times[k];
}

}  // namespace
}  // namespace mna::test

namespace mna::test {
namespace {

// A 1 V divider: R1 = 1 ohm from the source, below it S1 (VT 1, VH 0.5, RON 1, ROFF 1 Meg)
// controlled by v(ctl).
void switched_divider(CircuitSpec& c) {
  c.add("v1", {"in", "0"}, 1.0);
  c.add("r1", {"in", "out"}, 1.0);
  c.add("s1", {"out", "0", "ctl", "0"}).model = {{"vt", 1.0}, {"vh", 0.5}, {"ron", 1.0}, {"roff", 1e6}};
}

TEST(Events, SwitchHysteresisThresholdsAreHitExactly) {
  // Control ramps 0 -> 2 V over 1 ms and back: on above VT + VH = 1.5 V (t = 0.75 ms), off
  // below VT - VH = 0.5 V (t = 1.75 ms). The switch (RON 1, ROFF 1 Meg) loads a 1 V divider.
  CircuitSpec c;
  c.add("vctl", {"ctl", "0"}).waveform = {Waveform::Shape::piecewise_linear, {0, 0, 1e-3, 2, 2e-3, 0}};
  switched_divider(c);
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, false);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 2u);
  EXPECT_NEAR(run.events[0].t, 0.75e-3, 1e-12);
  EXPECT_NEAR(run.events[1].t, 1.75e-3, 1e-12);
  const int out = unknown(m, "v(out)");
  EXPECT_NEAR(run.events[0].x_before[out], 1e6 / (1e6 + 1), 1e-12);
  EXPECT_NEAR(run.events[0].x_after[out], 0.5, 1e-12);
  EXPECT_NEAR(run.events[1].x_after[out], 1e6 / (1e6 + 1), 1e-12);
}

TEST(Events, SwitchControlRestingAtAThresholdKeepsTheState) {
  // ngspice's rule: on above VT + VH, off below VT - VH, the state kept at either threshold.
  // The control rises to VT - VH = 0.5 V exactly and rests (off stays off), goes to 2 V (on at
  // VT + VH = 1.5 V, t = 2 ms + 2/3 ms), and comes back to 0.5 V exactly and rests (on stays
  // on).
  CircuitSpec c;
  c.add("vctl", {"ctl", "0"}).waveform = {Waveform::Shape::piecewise_linear, {0, 0, 1e-3, 0.5, 2e-3, 0.5, 3e-3, 2, 4e-3, 0.5}};
  switched_divider(c);
  Model m(c, {.tstep = 1e-5, .tstop = 6e-3});
  const Simulation run = simulate(m, 6e-3, false);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 1u);
  EXPECT_NEAR(run.events[0].t, 2e-3 + 1e-3 / 1.5, 1e-12);
  EXPECT_NEAR(run.states.back()[unknown(m, "v(out)")], 0.5, 1e-12);
}

TEST(Events, ComparatorAndTimeConditionsInBehavioralSource) {
  // out = v(in) > 0.5 ? 1 : 0 with v(in) = 1000 t, plus u(time - 0.3 ms) * 2 V.
  using netlist::BinaryOperator;
  CircuitSpec c;
  c.add("v1", {"in", "0"}).waveform = {Waveform::Shape::piecewise_linear, {0, 0, 1e-3, 1}};
  auto& b = c.add("b1", {"out", "0"});
  b.expression = binary(BinaryOperator::add, conditional(binary(BinaryOperator::greater, voltage("in"), number(0.5)), number(1), number(0)),
                        binary(BinaryOperator::multiply, call("u", {binary(BinaryOperator::subtract, time(), number(0.3e-3))}), number(2)));
  c.add("r1", {"out", "0"}, 1e3);
  Model m(c, {.tstep = 1e-5, .tstop = 1e-3});
  const Simulation run = simulate(m, 1e-3, false);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 2u);
  const int out = unknown(m, "v(out)");
  EXPECT_NEAR(run.events[0].t, 0.3e-3, 1e-12);
  EXPECT_NEAR(run.events[0].x_after[out], 2, 1e-12);
  EXPECT_NEAR(run.events[1].t, 0.5e-3, 1e-11);  // within padae's root-finding resolution
  EXPECT_NEAR(run.events[1].x_after[out], 3, 1e-12);
}

TEST(Start, ControlledSourcesOperatingPoint) {
  // v(a) = 2 V; E doubles it, G drives 1 mA/V * v(a) into 1 k, H reads i(v1) (= -2 mA
  // through R1 = 1 k), F mirrors 3 i(v1) into 1 k.
  CircuitSpec c;
  c.add("v1", {"a", "0"}, 2.0);
  c.add("r1", {"a", "0"}, 1e3);
  c.add("e1", {"e", "0", "a", "0"}, 2.0);
  c.add("re", {"e", "0"}, 1e3);
  c.add("g1", {"0", "g", "a", "0"}, 1e-3);
  c.add("rg", {"g", "0"}, 1e3);
  c.add("h1", {"h", "0"}, 500.0).controls = {"v1"};
  c.add("rh", {"h", "0"}, 1e3);
  c.add("f1", {"0", "f"}, 3.0).controls = {"v1"};
  c.add("rf", {"f", "0"}, 1e3);
  Model m(c, {.tstep = 1e-6, .tstop = 1e-5});
  const Simulation run = simulate(m, 1e-5, false);
  ASSERT_TRUE(run.ok) << run.failure;
  const Vector& x = run.states.back();
  EXPECT_NEAR(x[unknown(m, "i(v1)")], -2e-3, 1e-15);
  EXPECT_NEAR(x[unknown(m, "v(e)")], 4.0, 1e-12);
  EXPECT_NEAR(x[unknown(m, "v(g)")], 2.0, 1e-12);   // 2 mA from ground into g, through 1 k
  EXPECT_NEAR(x[unknown(m, "v(h)")], -1.0, 1e-12);  // 500 ohm * -2 mA
  EXPECT_NEAR(x[unknown(m, "v(f)")], -6.0, 1e-12);  // 3 * -2 mA into f
}

TEST(Start, OperatingPointThroughFunctionsThatAreInfiniteAtTheFirstGuess) {
  // v(in) = 2 V; Newton starts with every node at 0, where sqrt's slope, ln and 1/x are
  // infinite; and abs(v(in)) starts on its branch for v(in) < 0, whose -v(in) takes sqrt
  // outside its domain as soon as v(in) moves to 2.
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 2.0);
  c.add("r1", {"in", "0"}, 1e3);
  auto add_source = [&](const std::string& name, netlist::ExpressionPtr expression) {
    c.add("b" + name, {name, "0"}).expression = std::move(expression);
    c.add("r" + name, {name, "0"}, 1e3);
  };
  add_source("root", call("sqrt", {voltage("in")}));
  add_source("log", call("ln", {voltage("in")}));
  add_source("inverse", binary(netlist::BinaryOperator::divide, number(1), voltage("in")));
  add_source("rootabs", call("sqrt", {call("abs", {voltage("in")})}));
  Model m(c, {.tstep = 1e-6, .tstop = 1e-5});
  const Simulation run = simulate(m, 1e-5, false);
  ASSERT_TRUE(run.ok) << run.failure;
  const Vector& x = run.states.front();
  EXPECT_NEAR(x[unknown(m, "v(root)")], std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(x[unknown(m, "v(log)")], std::log(2.0), 1e-12);
  EXPECT_NEAR(x[unknown(m, "v(inverse)")], 0.5, 1e-12);
  EXPECT_NEAR(x[unknown(m, "v(rootabs)")], std::sqrt(2.0), 1e-12);
}

TEST(Transient, SquareRootOfASourceThatTouchesZero) {
  // v(in) = 1 + cos(w t) touches 0 at t = 5 us, where a predictor extrapolates it below 0 and
  // sqrt(v(in)) cannot be evaluated: Newton starts from the step's start there instead.
  CircuitSpec c;
  c.add("v1", {"in", "0"}).waveform = {Waveform::Shape::sine, {1, 1, 1e5, 0, 0, 90}};
  c.add("r1", {"in", "0"}, 1e3);
  c.add("b1", {"out", "0"}).expression = call("sqrt", {voltage("in")});
  c.add("r2", {"out", "0"}, 1e3);
  Model m(c, {.tstep = 1e-8, .tstop = 2e-5});
  const Simulation run = simulate(m, 2e-5, false, 1e-6);
  ASSERT_TRUE(run.ok) << run.failure;
  const int out = unknown(m, "v(out)");
  for (std::size_t k = 0; k < run.times.size(); ++k) {
    const double exact = std::sqrt(std::max(0.0, 1 + std::cos(2 * std::numbers::pi * 1e5 * run.times[k])));
    EXPECT_NEAR(run.states[k][out], exact, 1e-6) << "t = " << run.times[k];
  }
}

TEST(Transient, SquareRootOfAbsOfARampFromZero) {
  // abs(v(in)) starts at its kink: v(in) = 0, its predicate off (-v(in)), and just after t = 0
  // sqrt(-v(in)) cannot be evaluated. The guards where the mode left its domain (v(in) > 0)
  // name the mode to take instead: v(out) = sqrt(t / 1 ms).
  CircuitSpec c;
  c.add("v1", {"in", "0"}).waveform = {Waveform::Shape::piecewise_linear, {0, 0, 1e-3, 1}};
  c.add("b1", {"out", "0"}).expression = call("sqrt", {call("abs", {voltage("in")})});
  c.add("r1", {"out", "0"}, 1e3);
  Model m(c, {.tstep = 1e-5, .tstop = 1e-3});
  const Simulation run = simulate(m, 1e-3, false, 1e-6);
  ASSERT_TRUE(run.ok) << run.failure;
  const int out = unknown(m, "v(out)");
  for (std::size_t k = 0; k < run.times.size(); ++k)
    EXPECT_NEAR(run.states[k][out], std::sqrt(run.times[k] / 1e-3), 1e-5) << "t = " << run.times[k];
  EXPECT_NEAR(run.times.back(), 1e-3, 1e-15);
}

TEST(Transient, SquareRootOfAbsOfASineCrossesItsZeros) {
  // sqrt(abs(sin(w t))): at each zero of the sine abs's live branch reaches sqrt's domain edge
  // together with its guard; the crossings are located as events (5 in 3 ms) and each half
  // period follows its own branch.
  CircuitSpec c;
  c.add("v1", {"in", "0"}).waveform = {Waveform::Shape::sine, {0, 1, 1e3}};
  c.add("b1", {"out", "0"}).expression = call("sqrt", {call("abs", {voltage("in")})});
  c.add("r1", {"out", "0"}, 1e3);
  Model m(c, {.tstep = 1e-5, .tstop = 3e-3});
  const Simulation run = simulate(m, 3e-3, false, 1e-6);
  ASSERT_TRUE(run.ok) << run.failure;
  EXPECT_NEAR(run.times.back(), 3e-3, 1e-15);
  ASSERT_EQ(run.events.size(), 5u);
  for (std::size_t k = 0; k < run.events.size(); ++k) EXPECT_NEAR(run.events[k].t, 0.5e-3 * (k + 1), 1e-12);
  const int out = unknown(m, "v(out)");
  for (std::size_t k = 0; k < run.times.size(); ++k) {
    const double exact = std::sqrt(std::abs(std::sin(2 * std::numbers::pi * 1e3 * run.times[k])));
    EXPECT_NEAR(run.states[k][out], exact, 2e-5) << "t = " << run.times[k];
  }
}

TEST(Transient, PicosecondModeAtACornerOfALongRunIsNotAJump) {
  // A 1 fs ramp to 1 V at 1 us into R = 1 ohm, C = 1 pF (tau = 1 ps), run to 1000 s: the
  // re-initialization's settling steps (1e-3 of steps near 20 s) see the RC settled in all
  // three, which made it a jump of C's charge through the resistor (v = 0.064 at the corner;
  // 0.44 at 5000 s). C's charge cannot move at the corner: v = 1 - exp(-(t - t1) / tau) after it.
  CircuitSpec c;
  const double t1 = 1e-6 + 1e-15, tau = 1e-12;
  c.add("vs", {"s", "0"}).waveform = {Waveform::Shape::piecewise_linear, {0, 0, 1e-6, 0, t1, 1}};
  c.add("r1", {"s", "n1"}, 1.0);
  c.add("c1", {"n1", "0"}, 1e-12);
  Model m(c, {.tstep = 1e-9, .tstop = 1e3});
  const Simulation run = simulate(m, 1e3, false, 1e-3);
  ASSERT_TRUE(run.ok) << run.failure;
  const int n1 = unknown(m, "v(n1)");
  int after_corner = 0;
  for (std::size_t k = 0; k < run.times.size(); ++k) {
    const double t = run.times[k];
    if (t < t1) {
      EXPECT_NEAR(run.states[k][n1], 0, 1e-3) << "t = " << t;
    } else {
      // Within the ramp's 1 fs of the ideal step's response, and the tolerance.
      EXPECT_NEAR(run.states[k][n1], 1 - std::exp(-(t - t1) / tau), 2e-3) << "t = " << t;
      if (t < t1 + 10 * tau) ++after_corner;
    }
  }
  EXPECT_GE(after_corner, 3);  // the rise is resolved, not jumped over
}

TEST(Start, ShockleyDiodeOperatingPointSatisfiesItsEquation) {
  // 5 V through 1 k into a diode: i = IS (exp(v / (N Vt)) - 1) + GMIN v = (5 - v) / 1 k.
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 5.0);
  c.add("r1", {"in", "a"}, 1e3);
  c.add("d1", {"a", "0"}).model = {{"is", 1e-14}, {"n", 1.0}};
  Model m(c, {.tstep = 1e-6, .tstop = 1e-5});
  const Simulation run = simulate(m, 1e-5, false);
  ASSERT_TRUE(run.ok) << run.failure;
  const double v = run.states.back()[unknown(m, "v(a)")];
  const double vt = 1.38064852e-23 * 300.15 / 1.6021766208e-19;
  EXPECT_NEAR(1e-14 * (std::exp(v / vt) - 1) + 1e-12 * v, (5 - v) / 1e3, 1e-9);
  EXPECT_GT(v, 0.6);
  EXPECT_LT(v, 0.75);
}

// circuits/boost.cir: the inductor ramps down through the diode until the junction blocks
// (discontinuous conduction), then rests at v(sw) / ROFF (0.5 uA). Neither the inductor's current
// nor the switch node goes below zero: no path carries the current back. At rtol 1e-2 the
// steps reached the turn-off on a matrix factored while the junction conducted amps, 1000 times
// stiffer than near zero current behind its 5 mOhm; Newton on it called -92 mA through the
// blocked junction converged, and v(sw) fell to -32 kV when the steps' current snapped back.
// Once the diode blocks, ROFF alone holds the node, at Vin - L di/dt: BDF2's derivative across
// the turn-off took it to -0.86 V at rtol 1e-3 and 1.55 V at 1e-4 (the step is now retaken at
// order 1, System::kinks, also where the formula's history reaches back across the turn-off).
// From rtol 1.5e-2 up, Newton took states 2 V short of the junction's turn-off as converged (the
// 18 V node's tolerance is 9 N VT): i(l1) -12 mA against the junction's +24 mA, then -14 kV at
// v(sw) as ROFF took that current (System::currents_converged now checks the junction's current).
TEST(Transient, BoostInDiscontinuousConductionNeverDrivesItsCurrentBackThroughTheDiode) {
  CircuitSpec c;
  c.add("vin", {"in", "0"}, 5.0);
  c.add("vdrv", {"drv", "0"}).waveform = {Waveform::Shape::pulse, {0, 5, 0, 10e-9, 10e-9, 6e-6, 10e-6}};
  c.add("l1", {"in", "sw"}, 22e-6);
  c.add("s1", {"sw", "0", "drv", "0"}).model = {{"vt", 2.5}, {"vh", 0.0}, {"ron", 10e-3}, {"roff", 10e6}};
  c.add("d1", {"sw", "out"}).model = {{"is", 1e-9}, {"n", 1.5}, {"rs", 5e-3}};
  c.add("c1", {"out", "0"}, 47e-6);
  c.add("rload", {"out", "0"}, 20.0);
  for (double rtol : {5e-2, 3e-2, 2e-2, 1.5e-2, 1e-2, 5e-3, 3e-3, 2.5e-3, 2e-3, 1e-3, 1e-4}) {
    Model m(c, {.tstep = 50e-9, .tstop = 500e-6});
    const Simulation run = simulate(m, 500e-6, false, rtol, Tolerances{});
    ASSERT_TRUE(run.ok) << run.failure;
    const int current = unknown(m, "i(l1)"), node = unknown(m, "v(sw)"), drive = unknown(m, "v(drv)");
    double lowest_current = 0, lowest_node = 0, lowest_node_switch_off = 5.0;
    for (const Vector& state : run.states) {
      lowest_current = std::min(lowest_current, state[current]);
      lowest_node = std::min(lowest_node, state[node]);
      if (state[drive] == 0) lowest_node_switch_off = std::min(lowest_node_switch_off, state[node]);
    }
    // An error-tested current within a few tolerances (rtol of 1e-3 of its 2.5 A peak); v(sw)
    // RON times it while the switch conducts, at least Vin while it blocks (v(out) + the diode's
    // drop, then Vin).
    EXPECT_GT(lowest_current, -4 * rtol * 2.5e-3) << "rtol " << rtol;
    EXPECT_GT(lowest_node, -rtol) << "rtol " << rtol;
    EXPECT_GT(lowest_node_switch_off, 5.0 * (1 - 10 * rtol)) << "rtol " << rtol;
  }
}

// -281 V steps through 50 uH into a diode pair and a capacitor that float on 1 MOhm (uic, one
// leg of a bridge rectifier). The inductor's current, held to 1 pA, made IDA's first step 2e-19
// s, where C / h swamps the 1 uS holding the island's common mode in every row of the matrix:
// Newton failed however small the step (RS = 0) or half the time, for ever (RS = 5 mOhm), at
// every rtol. Within picoseconds the current settles (L / R = 50 ps) to what Rref carries
// through D5: v(neg) = -281 + n VT ln(1 + (-v(neg) / Rref) / IS), ngspice's -280.33467 V. D2
// blocks, so the capacitor only drifts by IS t / C (1e-8 V at 1 ms).
TEST(Start, DiodeIslandOnOneMegohmStartsFromInitialConditionsAtEveryTolerance) {
  const double is = 1e-11, n = 1.5, rref = 1e6;
  const double vte = n * 1.38064852e-23 * 300.15 / 1.6021766208e-19;  // ngspice's constants
  double settled = -280;
  for (int i = 0; i < 50; ++i) settled = -281 + vte * std::log1p(-settled / (rref * is));
  for (double rs : {0.0, 5e-3}) {
    CircuitSpec c;
    c.add("vb", {"b0", "0"}, -281.0);
    c.add("lb", {"b0", "b"}, 50e-6);
    c.add("d2", {"b", "pos"}).model = {{"is", is}, {"n", n}, {"rs", rs}};
    c.add("d5", {"neg", "b"}).model = {{"is", is}, {"n", n}, {"rs", rs}};
    c.add("rref", {"neg", "0"}, rref);
    c.add("cl", {"pos", "neg"}, 1e-6);
    for (double rtol : {1e-3, 1e-6, 1e-8}) {
      Model m(c, {.tstep = 10e-6, .tstop = 1e-3});
      const Simulation run = simulate(m, 1e-3, true, rtol);
      ASSERT_TRUE(run.ok) << "rs " << rs << ", rtol " << rtol << ": " << run.failure;
      const Vector& end = run.states.back();
      EXPECT_NEAR(end[unknown(m, "v(neg)")], settled, 1e-5) << "rs " << rs << ", rtol " << rtol;
      EXPECT_NEAR(end[unknown(m, "v(pos)")] - end[unknown(m, "v(neg)")], 0, 1e-7) << "rs " << rs << ", rtol " << rtol;
    }
  }
}

TEST(Events, FlyingCapacitorLeftFloatingSettlesOnItsResistiveCommonModeInAFewIterations) {
  // A charge pump's flying capacitor between its two phases: all four switches off, it floats
  // on four OFF resistances. Its voltage Vc is held, and KCL on the pair of its nodes gives
  // (in - top) + (out - top) + (in - bot) + (0 - bot) = 0 over ROFF: top = (in + out / 2 + Vc) / 2.
  // At the event the vanishing step's matrix (C / h of a 1e-20 s step against 1e-8 S) is too
  // ill-conditioned to refine the current through the capacitor (Vfly's: C / h per ulp of its
  // voltage); a longer step's is not. Refining it anyway ran into the iteration limit (100 per
  // attempt): 138 iterations per event instead of 37.
  const double vin = 5, roff = 100e6;
  CircuitSpec c;
  c.add("vin", {"in", "0"}, vin);
  c.add("vp1", {"p1", "0"}).waveform = {Waveform::Shape::pulse, {0, 5, 0.5e-6, 10e-9, 10e-9, 9e-6, 20e-6}};
  c.add("vp2", {"p2", "0"}).waveform = {Waveform::Shape::pulse, {0, 5, 10.5e-6, 10e-9, 10e-9, 9e-6, 20e-6}};
  auto add_switch = [&](const std::string& name, const std::string& a, const std::string& b, const std::string& drive) {
    c.add(name, {a, b, drive, "0"}).model = {{"vt", 2.5}, {"vh", 0.0}, {"ron", 1.0}, {"roff", roff}};
  };
  add_switch("s1", "in", "top", "p1");
  add_switch("s2", "bot0", "0", "p1");
  add_switch("s3", "in", "bot0", "p2");
  add_switch("s4", "top", "out", "p2");
  c.add("cfly", {"top", "bot"}, 1e-6);
  c.add("vfly", {"bot", "bot0"}, 0.0);  // measures its current
  c.add("cout", {"out", "0"}, 10e-6);
  c.add("rload", {"out", "0"}, 1e3);
  Model m(c, {.tstep = 20e-9, .tstop = 200e-6});
  const Simulation run = simulate(m, 200e-6, true, 1e-3, Tolerances{});
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_FALSE(run.events.empty());
  const int top = unknown(m, "v(top)"), bot = unknown(m, "v(bot)"), out = unknown(m, "v(out)");
  int floating = 0;
  for (const auto& event : run.events) {
    const Vector& x = event.x_after;
    const double held = x[top] - x[bot];
    EXPECT_NEAR(held, event.x_before[top] - event.x_before[bot], 1e-3 * vin) << "at t = " << event.t;
    // Every switch off: the drives are both low.
    const double phase = std::fmod(event.t, 20e-6);
    if (phase < 10e-6 ? phase > 9.5e-6 : phase > 19.5e-6) {
      ++floating;
      const double expected = (vin + x[out] / 2 + held) / 2;
      EXPECT_NEAR(x[top], expected, 1e-3 * vin) << "at t = " << event.t;
    }
  }
  EXPECT_GE(floating, 18);
  // Per event: its root location, the vanishing step, the settling steps and the steps between
  // events.
  const long per_event = run.statistics.newton_iterations / static_cast<long>(run.events.size());
  EXPECT_LT(per_event, 60) << run.statistics.newton_iterations << " iterations, " << run.events.size() << " events, "
                           << run.statistics.steps << " steps";
}

TEST(Start, ThreePhaseShockleyBridgeFedThroughInductorsFollowsItsLoop) {
  // A three-phase bridge of Shockley diodes with junction capacitance and series resistance,
  // fed through source inductances, into an RL load. The rectifier floats: only the three
  // inductors tie it to ground, so a current left in any of its algebraic rows at the start
  // is charge that nothing but L / h can carry away (the start failed at rtol >= 1e-5). From the
  // operating point until va reaches vc (wt = 30 deg), D5 and D6 carry the load current around
  // the loop vc -> Lc -> D5 -> Ld -> R -> D6 -> Lb -> vb:
  //     (Lb + Lc + Ld) di/dt = vc - vb - 2 vd(i) - R i,   vd(i) = N Vt ln(1 + i / IS) + RS i,
  // vc - vb = sqrt(3) Vm cos(wt), integrated here by RK4 from its DC solution (the junction
  // capacitances' currents, about 1 uA, are left out).
  const double vm = 100, w = 2 * std::numbers::pi * 50, ls = 2e-3, ld = 50e-3, r = 10;
  const double is = 1e-9, n = 1.5, rs = 10e-3, vt = n * 1.38064852e-23 * 300.15 / 1.6021766208e-19;
  CircuitSpec c;
  for (auto [source, node, phase] : {std::tuple{"va", "a", 0.0}, {"vb", "b", -120.0}, {"vc", "c", 120.0}}) {
    const std::string terminal = std::string("s") + node;
    c.add(source, {terminal, "0"}).waveform = {Waveform::Shape::sine, {0, vm, 50, 0, 0, phase}};
    c.add(std::string("l") + node, {terminal, node}, ls);
  }
  for (auto [name, anode, cathode] : {std::tuple{"d1", "a", "p"}, {"d3", "b", "p"}, {"d5", "c", "p"},
                                      {"d4", "n", "a"}, {"d6", "n", "b"}, {"d2", "n", "c"}})
    c.add(name, {anode, cathode}).model = {{"is", is}, {"n", n}, {"rs", rs}, {"cjo", 100e-12}};
  c.add("ld", {"p", "x"}, ld);
  c.add("rl", {"x", "n"}, r);
  // A 60 ms run at rtol 1e-4 with the command's default tolerances, checked to 1.5 ms.
  Model m(c, {.tstep = 1e-5, .tstop = 60e-3});
  const Simulation run = simulate(m, 60e-3, false, 1e-4, Tolerances{}, 1.5e-3);
  ASSERT_TRUE(run.ok) << run.failure;

  auto drop = [&](double i) { return vt * std::log1p(i / is) + rs * i; };
  auto slope = [&](double t, double i) {
    return (std::sqrt(3.0) * vm * std::cos(w * t) - 2 * drop(i) - r * i) / (2 * ls + ld);
  };
  double i = 17;  // DC: sqrt(3) Vm = 2 vd(i) + R i, by Newton
  for (int k = 0; k < 50; ++k) i -= (2 * drop(i) + r * i - std::sqrt(3.0) * vm) / (2 * (vt / (is + i) + rs) + r);
  const int load = unknown(m, "i(ld)");
  EXPECT_NEAR(run.states.front()[load], i, 1e-6);
  const double dt = 1e-8;
  double t = 0;
  for (std::size_t k = 1; k < run.times.size(); ++k) {
    for (; t + dt <= run.times[k]; t += dt) {
      const double k1 = slope(t, i), k2 = slope(t + dt / 2, i + dt / 2 * k1), k3 = slope(t + dt / 2, i + dt / 2 * k2),
                   k4 = slope(t + dt, i + dt * k3);
      i += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    const double rest = run.times[k] - t;
    const double reference = i + rest * slope(t, i);
    EXPECT_NEAR(run.states[k][load], reference, 1e-3) << "t = " << run.times[k];  // rtol 1e-4 of 17 A
  }
}

}  // namespace
}  // namespace mna::test

namespace mna::test {
namespace {

TEST(Transient, CoupledInductorInducesMdiDt) {
  // Primary: 1 V through R = 2 ohm into L1 = 4 mH, i1 = (1 - e^(-t R / L1)) / R; secondary L2 =
  // 1 mH into 1 G (open): v2 = M di1/dt = M / L1 e^(-t R / L1), M = k sqrt(L1 L2), once the
  // secondary's own transient, L2 (1 - k^2) / 1 G = 0.36 ps, is over (checked from 1 ns on).
  const double l1 = 4e-3, l2 = 1e-3, k = 0.8, r = 2, mutual = k * std::sqrt(l1 * l2);
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 1.0);
  c.add("r1", {"in", "a"}, r);
  c.add("l1", {"a", "0"}, l1).initial_condition = 0.0;
  c.add("l2", {"s", "0"}, l2).initial_condition = 0.0;
  c.add("k1", {}, k).controls = {"l1", "l2"};
  c.add("r2", {"s", "0"}, 1e9);
  Model m(c, {.tstep = 1e-5, .tstop = 4e-3});
  const Simulation run = simulate(m, 4e-3, true);
  ASSERT_TRUE(run.ok) << run.failure;
  const int s = unknown(m, "v(s)"), i1 = unknown(m, "i(l1)");
  std::size_t checked = 0;
  for (std::size_t n = 0; n < run.times.size(); ++n) {
    const double t = run.times[n], decay = std::exp(-t * r / l1);
    if (t < 1e-9) continue;
    ++checked;
    EXPECT_NEAR(run.states[n][i1], (1 - decay) / r, 1e-5) << "t = " << t;
    EXPECT_NEAR(run.states[n][s], mutual / l1 * decay, 1e-5) << "t = " << t;
  }
  EXPECT_GT(checked, 10u);
}

TEST(Events, CurrentSwitchFollowsItsControllingCurrent) {
  // A current ramp 0 -> 1 mA -> 0 through Vsense controls W1 (IT = 0.5 mA, IH = 0.1 mA): on
  // at 0.6 mA (t = 0.6 ms), off at 0.4 mA (t = 1.6 ms).
  CircuitSpec c;
  c.add("i1", {"0", "x"}).waveform = {Waveform::Shape::piecewise_linear, {0, 0, 1e-3, 1e-3, 2e-3, 0}};
  c.add("vsense", {"x", "0"}, 0.0);
  c.add("v1", {"in", "0"}, 1.0);
  c.add("r1", {"in", "out"}, 1.0);
  auto& w = c.add("w1", {"out", "0"});
  w.controls = {"vsense"};
  w.model = {{"it", 0.5e-3}, {"ih", 0.1e-3}, {"ron", 1.0}, {"roff", 1e6}};
  Model m(c, {.tstep = 1e-5, .tstop = 2e-3});
  const Simulation run = simulate(m, 2e-3, false);
  ASSERT_TRUE(run.ok) << run.failure;
  ASSERT_EQ(run.events.size(), 2u);
  // Located where the interpolated current crosses the threshold: to 1e-10 s here is 1e-13 A
  // of current (1 A/s ramp), below its absolute tolerance.
  EXPECT_NEAR(run.events[0].t, 0.6e-3, 1e-10);
  EXPECT_NEAR(run.events[1].t, 1.6e-3, 1e-10);
  EXPECT_NEAR(run.events[0].x_after[unknown(m, "v(out)")], 0.5, 1e-12);
}

}  // namespace
}  // namespace mna::test
