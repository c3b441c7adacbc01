// Each device's load against hand-derived f, q and Jacobians.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "helpers.hpp"

namespace mna::test {
namespace {

constexpr double thermal_voltage = 1.38064852e-23 * 300.15 / 1.6021766208e-19;

TEST(DeviceLoad, ResistorConductsFromHighToLowNode) {
  CircuitSpec c;
  c.add("r1", {"a", "b"}, 2.0);
  Model m(c, {});
  Vector x(2);
  x << 3, 1;
  const auto l = evaluate(m, 0, x, {});
  EXPECT_DOUBLE_EQ(l.f[0], 1.0);  // (3 - 1) / 2 leaves node a
  EXPECT_DOUBLE_EQ(l.f[1], -1.0);
  Eigen::Matrix2d g;
  g << 0.5, -0.5, -0.5, 0.5;
  EXPECT_TRUE(l.df.isApprox(g));
  EXPECT_TRUE(l.q.isZero());
}

TEST(DeviceLoad, CapacitorChargeAndStoredEnergy) {
  CircuitSpec c;
  c.add("c1", {"a", "0"}, 1e-6);
  Model m(c, {});
  Vector x(1);
  x << 4;
  const auto l = evaluate(m, 0, x, {});
  EXPECT_DOUBLE_EQ(l.q[0], 4e-6);
  EXPECT_DOUBLE_EQ(l.dq(0, 0), 1e-6);
  EXPECT_EQ(m.kind(0), padae::UnknownKind::differential);
  EXPECT_DOUBLE_EQ(m.stored_energy(x), 0.5 * 1e-6 * 16);
}

TEST(DeviceLoad, FloatingCapacitorCarriesItsCurrentAndHoldsItsChargeInItsOwnRow) {
  CircuitSpec c;
  c.add("c1", {"a", "b"}, 2e-6);
  Model m(c, {});
  const int a = unknown(m, "v(a)"), b = unknown(m, "v(b)"), i = unknown(m, "i(c1)");
  Vector x(3);
  x[a] = 5, x[b] = 2, x[i] = 0.25;
  const auto l = evaluate(m, 0, x, {});
  EXPECT_DOUBLE_EQ(l.f[a], 0.25);  // i leaves node a through the capacitor into b
  EXPECT_DOUBLE_EQ(l.f[b], -0.25);
  EXPECT_DOUBLE_EQ(l.f[i], -0.25);  // d/dt q - i = 0
  EXPECT_DOUBLE_EQ(l.q[i], 2e-6 * 3);
  EXPECT_EQ(l.q[a], 0.0);  // the node rows hold no charge: C/h never meets their conductances
  EXPECT_EQ(l.q[b], 0.0);
  EXPECT_DOUBLE_EQ(l.dq(i, a), 2e-6);
  EXPECT_DOUBLE_EQ(l.dq(i, b), -2e-6);
  EXPECT_DOUBLE_EQ(l.df(a, i), 1.0);
  EXPECT_DOUBLE_EQ(l.df(b, i), -1.0);
  EXPECT_DOUBLE_EQ(l.df(i, i), -1.0);
  EXPECT_EQ(m.kind(a), padae::UnknownKind::differential);
  EXPECT_EQ(m.kind(i), padae::UnknownKind::algebraic);
  EXPECT_DOUBLE_EQ(m.stored_energy(x), 0.5 * 2e-6 * 9);
  // Its current is the device's own: no element or probe names it as a branch.
  EXPECT_FALSE(m.unknowns().has_branch("c1"));
}

// A junction between two nodes off ground is a ChargeBranch too: its charge (depletion plus
// TT times the current) in its own row, d/dt q - i = 0, the node rows +-i besides the junction's
// current. Depletion charge: VJ CJO (1 - (1 - v / VJ)^(1 - M)) / (1 - M) below FC VJ.
TEST(DeviceLoad, FloatingJunctionCarriesItsChargesCurrent) {
  CircuitSpec c;
  c.add("d1", {"a", "k"}).model = {{"is", 1e-14}, {"cjo", 2e-9}, {"vj", 0.7}, {"m", 0.4}, {"tt", 1e-8}};
  Model m(c, {});
  const int a = unknown(m, "v(a)"), k = unknown(m, "v(k)"), i = unknown(m, "i(d1#junction)");
  Vector x(3);
  x[a] = 1.5, x[k] = 4.5, x[i] = 0.125;  // reverse-biased by 3 V
  const auto l = evaluate(m, 0, x, {});
  const double v = -3, current = -1e-14 + 1e-12 * v;  // the cubic's limit far below -3 N Vt, and GMIN
  EXPECT_NEAR(l.f[a], current + 0.125, 1e-15);
  EXPECT_NEAR(l.f[k], -current - 0.125, 1e-15);
  EXPECT_DOUBLE_EQ(l.f[i], -0.125);
  const double depletion = 0.7 * 2e-9 * (1 - std::pow(1 - v / 0.7, 1 - 0.4)) / (1 - 0.4);
  EXPECT_NEAR(l.q[i], depletion + 1e-8 * (-1e-14), 1e-12 * std::abs(depletion));
  EXPECT_EQ(l.q[a], 0.0);
  EXPECT_EQ(l.q[k], 0.0);
  const double capacitance = 2e-9 * std::pow(1 - v / 0.7, -0.4);  // TT's part: TT times ~0 S
  EXPECT_NEAR(l.dq(i, a), capacitance, 1e-9 * capacitance);
  EXPECT_NEAR(l.dq(i, k), -capacitance, 1e-9 * capacitance);
  EXPECT_DOUBLE_EQ(l.df(a, i), 1.0);
  EXPECT_DOUBLE_EQ(l.df(k, i), -1.0);
  EXPECT_DOUBLE_EQ(l.df(i, i), -1.0);
  EXPECT_EQ(m.kind(a), padae::UnknownKind::differential);
  EXPECT_FALSE(m.unknowns().has_branch("d1"));
  // A grounded junction keeps its charge in its node's row, as a grounded capacitor does.
  CircuitSpec grounded;
  grounded.add("d1", {"a", "0"}).model = {{"cjo", 2e-9}, {"vj", 0.7}, {"m", 0.4}};
  Model g(grounded, {});
  Vector y(1);
  y << v;
  EXPECT_EQ(g.size(), 1);
  EXPECT_NEAR(evaluate(g, 0, y, {}).q[0], depletion, 1e-12 * std::abs(depletion));
}

TEST(DeviceLoad, ChargesFromAReferenceCancelExactlyAcrossTheirPairOfRows) {
  // A MOSFET's bulk-drain junction (CBD = 10 uF, its charge in the node rows) reverse-biased by
  // 156 V between bulk p and drain n holds some 2e-4 C, 100 pF from each to ground. Measured from
  // a reference state, each row sums changes: p's and n's rows add up to the small capacitors'
  // changes alone (3e-17 C) to those changes' rounding, where absolute charges round each row by
  // some 4e-20 C, differently.
  CircuitSpec c;
  c.add("m1", {"n", "0", "0", "p"}, 1).model = {{"cbd", 1e-5}, {"pb", 0.8}, {"mj", 0.5}, {"vto", 1}};
  c.add("c1", {"p", "0"}, 1e-10);
  c.add("c2", {"n", "0"}, 1e-10);
  Model m(c, {});
  const int p = unknown(m, "v(p)"), n = unknown(m, "v(n)");
  Vector reference(2), moved(2);
  reference[p] = 0.2, reference[n] = 156.3;
  moved = reference;
  moved[p] += 1e-7, moved[n] += 2e-7;
  ASSERT_TRUE(m.measure_charges_from(0, reference, {}));
  EXPECT_TRUE(evaluate(m, 0, reference, {}).q.isZero(0));
  const auto l = evaluate(m, 0, moved, {});
  const double grounded_change = 1e-10 * (moved[p] - reference[p]) + 1e-10 * (moved[n] - reference[n]);
  EXPECT_NEAR(l.q[p] + l.q[n], grounded_change, 1e-22);
  // The junction's change: its capacitance at -156.1 V, (1 + 156.1 / 0.8)^-0.5 CBD, times 1e-7 V.
  const double junction_change = 1e-5 / std::sqrt(1 + 156.1 / 0.8) * ((moved[p] - moved[n]) - (reference[p] - reference[n]));
  EXPECT_NEAR(l.q[p], junction_change + 1e-10 * (moved[p] - reference[p]), 1e-3 * std::abs(junction_change));
}

TEST(DeviceLoad, CoupledInductorsFluxRows) {
  CircuitSpec c;
  c.add("l1", {"a", "0"}, 4e-3);
  c.add("l2", {"b", "0"}, 1e-3);
  auto& k = c.add("k1", {}, 0.5);
  k.controls = {"l1", "l2"};
  Model m(c, {});
  const int i1 = unknown(m, "i(l1)"), i2 = unknown(m, "i(l2)");
  Vector x(4);
  x << 2, 1, 0.3, -0.2;  // v(a), v(b), i(l1), i(l2)
  ASSERT_EQ(i1, 2);
  ASSERT_EQ(i2, 3);
  const auto l = evaluate(m, 0, x, {});
  const double mutual = 0.5 * std::sqrt(4e-3 * 1e-3);
  EXPECT_DOUBLE_EQ(l.f[0], 0.3);  // the branch current leaves node a
  EXPECT_DOUBLE_EQ(l.f[i1], 2.0); // v(a) - 0
  EXPECT_DOUBLE_EQ(l.q[i1], -(4e-3 * 0.3 + mutual * -0.2));
  EXPECT_DOUBLE_EQ(l.q[i2], -(1e-3 * -0.2 + mutual * 0.3));
  EXPECT_DOUBLE_EQ(l.dq(i1, i2), -mutual);
  EXPECT_DOUBLE_EQ(m.stored_energy(x), 0.5 * 4e-3 * 0.09 + 0.5 * 1e-3 * 0.04 + mutual * 0.3 * -0.2);
}

TEST(DeviceLoad, VoltageSourceFollowsItsWaveform) {
  CircuitSpec c;
  auto& v = c.add("v1", {"a", "0"});
  v.waveform = {Waveform::Shape::pulse, {0, 5, 1e-3, 1e-3, 1e-3, 2e-3, 10e-3}};
  c.add("r1", {"a", "0"}, 1.0);
  Model m(c, {.tstep = 1e-4, .tstop = 10e-3});
  Vector x(2);
  x << 1, 0.5;
  const auto l = evaluate(m, 1.5e-3, x, {});
  EXPECT_DOUBLE_EQ(l.f[1], 1 - 2.5);  // v(a) - V(t), V halfway up the rise
  EXPECT_DOUBLE_EQ(l.f[0], 0.5 + 1.0);
  EXPECT_DOUBLE_EQ(m.next_time_event(1.5e-3), 2e-3);
  // The source delivers -V * (charge through it) during a jump.
  Vector impulse = Vector::Zero(2);
  impulse[1] = -1e-6;
  EXPECT_DOUBLE_EQ(m.devices()[0]->delivered_energy(2.5e-3, impulse), 5 * 1e-6);
}

TEST(DeviceLoad, ControlledSources) {
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 1.0);
  c.add("e1", {"o1", "0", "in", "0"}, 3.0);
  c.add("g1", {"o2", "0", "in", "0"}, 2.0).controls = {};
  c.add("f1", {"o3", "0"}, 4.0).controls = {"v1"};
  c.add("h1", {"o4", "0"}, 5.0).controls = {"v1"};
  Model m(c, {});
  Vector x = Vector::LinSpaced(m.size(), 1, m.size());
  const int in = unknown(m, "v(in)"), o1 = unknown(m, "v(o1)"), o2 = unknown(m, "v(o2)"), o3 = unknown(m, "v(o3)"),
            o4 = unknown(m, "v(o4)"), iv = unknown(m, "i(v1)"), ie = unknown(m, "i(e1)"), ih = unknown(m, "i(h1)");
  const auto l = evaluate(m, 0, x, {});
  EXPECT_DOUBLE_EQ(l.f[ie], x[o1] - 3 * x[in]);
  EXPECT_DOUBLE_EQ(l.f[o2], 2 * x[in]);
  EXPECT_DOUBLE_EQ(l.f[o3], 4 * x[iv]);
  EXPECT_DOUBLE_EQ(l.f[ih], x[o4] - 5 * x[iv]);
  EXPECT_DOUBLE_EQ(l.df(ie, in), -3);
  EXPECT_DOUBLE_EQ(l.df(ih, iv), -5);
}

TEST(DeviceLoad, VoltageSwitchHysteresisGuardAndState) {
  CircuitSpec c;
  c.add("v1", {"ctl", "0"}, 0.0);
  auto& s = c.add("s1", {"a", "0", "ctl", "0"});
  s.model = {{"vt", 1.0}, {"vh", 0.2}, {"ron", 2.0}, {"roff", 1e6}};
  c.add("r1", {"a", "0"}, 1.0);
  Model m(c, {});
  const int ctl = unknown(m, "v(ctl)"), a = unknown(m, "v(a)"), state = unknown(m, "state(s1)");
  ASSERT_GE(state, 0);
  EXPECT_EQ(m.kind(state), padae::UnknownKind::auxiliary);
  ASSERT_EQ(m.predicate_count(), 1);
  Vector x = Vector::Zero(m.size());
  x[ctl] = 1.1, x[a] = 4;
  Vector guard(1);
  m.guards(0, x, guard);
  EXPECT_NEAR(guard[0], 1.1 - 1.2, 1e-15);  // off: turns on above VT + VH
  x[state] = 1;
  m.guards(0, x, guard);
  EXPECT_NEAR(guard[0], 1.1 - 0.8, 1e-15);  // on: stays on down to VT - VH
  EXPECT_DOUBLE_EQ(evaluate(m, 0, x, {1}).f[a], 4 / 2.0 + 4 / 1.0);
  EXPECT_DOUBLE_EQ(evaluate(m, 0, x, {0}).f[a], 4 / 1e6 + 4 / 1.0);
  std::vector<padae::JumpEntry> jumps;
  m.jump_matrix(0, x, {1}, jumps);
  ASSERT_EQ(jumps.size(), 1u);
  EXPECT_EQ(jumps[0].row, state);
  EXPECT_EQ(jumps[0].value, 1.0);
}

TEST(DeviceLoad, IdealSwitchBranchRows) {
  CircuitSpec c;
  c.add("v1", {"ctl", "0"}, 0.0);
  c.add("s1", {"a", "b", "ctl", "0"}).model = {{"ron", 0.0}, {"roff", infinity}};
  c.add("r1", {"a", "0"}, 1.0);
  c.add("r2", {"b", "0"}, 1.0);
  Model m(c, {});
  const int a = unknown(m, "v(a)"), b = unknown(m, "v(b)"), i = unknown(m, "i(s1)");
  ASSERT_GE(i, 0);
  Vector x = Vector::Zero(m.size());
  x[a] = 3, x[b] = 1, x[i] = 0.25;
  const auto on = evaluate(m, 0, x, {1});
  EXPECT_DOUBLE_EQ(on.f[i], 2.0);  // v(a) - v(b) = 0 when closed
  EXPECT_DOUBLE_EQ(on.df(i, i), 0.0);
  const auto off = evaluate(m, 0, x, {0});
  EXPECT_DOUBLE_EQ(off.f[i], -0.25);  // i = 0 when open
  EXPECT_DOUBLE_EQ(off.df(i, a), 0.0);
  EXPECT_DOUBLE_EQ(off.df(i, i), -1.0);
  EXPECT_DOUBLE_EQ(off.f[a], 3 + 0.25);
}

TEST(DeviceLoad, IdealSwitchModelFlag) {
  // IDEAL=1: RON = 0 and ROFF = infinite unless given.
  CircuitSpec c;
  c.add("v1", {"ctl", "0"}, 0.0);
  c.add("s1", {"a", "0", "ctl", "0"}).model = {{"ideal", 1}};
  c.add("r1", {"a", "0"}, 1.0);
  Model m(c, {});
  const int a = unknown(m, "v(a)"), i = unknown(m, "i(s1)");
  ASSERT_GE(i, 0);
  Vector x = Vector::Zero(m.size());
  x[a] = 2, x[i] = 0.5;
  EXPECT_DOUBLE_EQ(evaluate(m, 0, x, {1}).f[i], 2.0);   // closed: v(a) = 0
  EXPECT_DOUBLE_EQ(evaluate(m, 0, x, {0}).f[i], -0.5);  // open: i = 0
}

TEST(DeviceLoad, IdealDiodeModeGuard) {
  CircuitSpec c;
  c.add("d1", {"a", "k"}).model = {{"ideal", 1}, {"vfwd", 0.7}, {"ron", 0.1}};
  c.add("r1", {"a", "0"}, 1.0);
  c.add("r2", {"k", "0"}, 1.0);
  Model m(c, {});
  const int a = unknown(m, "v(a)"), k = unknown(m, "v(k)"), i = unknown(m, "i(d1)"), mode = unknown(m, "mode(d1)");
  Vector x = Vector::Zero(m.size());
  x[a] = 2, x[k] = 1, x[i] = -0.5;
  Vector guard(1);
  m.guards(0, x, guard);
  EXPECT_DOUBLE_EQ(guard[0], 2 - 1 - 0.7);  // off: turns on when v exceeds VFWD
  x[mode] = 1;
  m.guards(0, x, guard);
  EXPECT_DOUBLE_EQ(guard[0], -0.5);  // on: turns off when the current falls below 0
  EXPECT_DOUBLE_EQ(evaluate(m, 0, x, {1}).f[i], (1 - 0.7) / 0.1 - -0.5);
  EXPECT_DOUBLE_EQ(evaluate(m, 0, x, {0}).f[i], 0.5);  // open: -i
}

TEST(DeviceLoad, IdealDiodeCharacteristicIsContinuousAtTheKnee) {
  // RON 0.1, ROFF 1e3, VFWD 0.7: off i = v / 1e3 up to the knee (0.7 V, 0.7 mA); on, the line
  // of slope 10 through the knee. The on -> off guard is the current's distance to the knee's.
  CircuitSpec c;
  c.add("d1", {"a", "0"}).model = {{"ideal", 1}, {"vfwd", 0.7}, {"ron", 0.1}, {"roff", 1e3}};
  c.add("r1", {"a", "0"}, 1.0);
  Model m(c, {});
  const int a = unknown(m, "v(a)"), i = unknown(m, "i(d1)"), mode = unknown(m, "mode(d1)");
  const double knee_current = 0.7 / 1e3;
  Vector x = Vector::Zero(m.size());
  x[a] = 0.7, x[i] = knee_current;  // the knee: both modes' rows vanish
  EXPECT_NEAR(evaluate(m, 0, x, {1}).f[i], 0.0, 1e-15);
  EXPECT_NEAR(evaluate(m, 0, x, {0}).f[i], 0.0, 1e-15);
  x[a] = 1.2, x[i] = 2.0;
  EXPECT_NEAR(evaluate(m, 0, x, {1}).f[i], (1.2 - 0.7) / 0.1 - (2.0 - knee_current), 1e-12);
  EXPECT_NEAR(evaluate(m, 0, x, {0}).f[i], 1.2 / 1e3 - 2.0, 1e-12);
  x[mode] = 1, x[i] = 1e-4;
  Vector guard(1);
  m.guards(0, x, guard);
  EXPECT_NEAR(guard[0], 1e-4 - knee_current, 1e-18);  // below the knee's current: turns off
}

TEST(DeviceLoad, ShockleyDiodeMatchesNgspiceEquations) {
  CircuitSpec c;
  auto& d = c.add("d1", {"a", "0"});
  d.model = {{"is", 1e-14}, {"n", 1.5}, {"cjo", 2e-12}, {"vj", 0.8}, {"m", 0.4}};
  Model m(c, {});
  const double vte = 1.5 * thermal_voltage;
  Vector x(1);
  x << 0.6;
  auto l = evaluate(m, 0, x, {});
  EXPECT_NEAR(l.f[0], 1e-14 * (std::exp(0.6 / vte) - 1) + 1e-12 * 0.6, 1e-12 * std::abs(l.f[0]));
  EXPECT_NEAR(l.df(0, 0), 1e-14 * std::exp(0.6 / vte) / vte + 1e-12, 1e-12 * l.df(0, 0));
  // Above FC*VJ = 0.4 the depletion capacitance is extrapolated linearly.
  const double f2 = std::pow(0.5, 1.4), f3 = 1 - 0.5 * 1.4;
  EXPECT_NEAR(l.dq(0, 0), 2e-12 / f2 * (f3 + 0.4 * 0.6 / 0.8), 1e-24);
  x << 0.3;
  l = evaluate(m, 0, x, {});
  EXPECT_NEAR(l.q[0], 0.8 * 2e-12 * (1 - std::pow(1 - 0.3 / 0.8, 0.6)) / 0.6, 1e-25);
  x << -1.0;  // reverse: SPICE's cubic approach to -IS
  l = evaluate(m, 0, x, {});
  const double arg = std::pow(3 * vte / (-1.0 * std::numbers::e), 3);
  EXPECT_NEAR(l.f[0], -1e-14 * (1 + arg) - 1e-12, 1e-26);
}

// Newton's steps into conduction and into breakdown are limited as ngspice's DEVpnjlim limits
// them (devsup.c, the Berkeley form): VCRIT = VTE ln(VTE / (sqrt 2 IS)); a step past VCRIT by
// more than 2 VTE stops at VTE ln(v_next / VTE) from reverse bias, at v + VTE ln(1 + (v_next -
// v) / VTE) from forward bias. Breakdown: the same on -(v + BV) (BV is the knee here).
TEST(DeviceLoad, ShockleyDiodeLimitsNewtonStepsAsPnjlim) {
  CircuitSpec c;
  c.add("d1", {"a", "0"}).model = {{"is", 1e-9}, {"n", 1.5}, {"bv", 50}, {"ibv", 1e-9}};
  Model m(c, {});
  const double vte = 1.5 * thermal_voltage, vcrit = vte * std::log(vte / (std::numbers::sqrt2 * 1e-9));
  auto limited = [&](double v, double v_next) {
    Vector x(1), x_next(1);
    x << v, x_next << v_next;
    return v + m.newton_step_fraction(x, x_next) * (v_next - v);
  };
  EXPECT_NEAR(limited(-24, 2e7), vte * std::log(2e7 / vte), 1e-12);
  EXPECT_NEAR(limited(0.5, 3), 0.5 + vte * std::log(1 + 2.5 / vte), 1e-12);
  EXPECT_EQ(limited(0.5, vcrit - 1e-3), vcrit - 1e-3);  // ends below VCRIT
  EXPECT_EQ(limited(0.7, 0.7 + 1.9 * vte), 0.7 + 1.9 * vte);  // within 2 VTE
  EXPECT_EQ(limited(0.7, -30), -30);  // reverse: the cubic is tame
  // IBV = IS: the knee is BV itself (diotemp.c).
  EXPECT_NEAR(limited(-49, -1e4), -50 - vte * std::log((1e4 - 50) / vte), 1e-9);
}

TEST(DeviceLoad, DiodeJunctionEnergyIsTheIntegralOfVdq) {
  // Below FC VJ: E(v) = integral of u CJO (1 - u/VJ)^-M du, closed form for M = 0.5:
  // with s = 1 - u/VJ: E = CJO VJ^2 [ (2/3) s^(3/2) - 2 s^(1/2) ] from s(0) = 1 to s(v).
  CircuitSpec c;
  c.add("d1", {"a", "0"}).model = {{"cjo", 1e-12}, {"vj", 0.8}, {"m", 0.5}, {"fc", 0.5}};
  Model m(c, {});
  Vector x(1);
  x << -2.0;
  const double s = 1 + 2.0 / 0.8;
  auto primitive = [](double s) { return 2.0 / 3.0 * std::pow(s, 1.5) - 2 * std::sqrt(s); };
  const double expected = 1e-12 * 0.8 * 0.8 * (primitive(s) - primitive(1));
  EXPECT_NEAR(m.stored_energy(x), expected, 1e-9 * expected);
}

// The level-1 MOSFET against Shichman and Hodges' closed form (the equations ngspice's
// mos1load.c evaluates): I = KP W / L (1 + LAMBDA vds) (vgs - VT)^2 / 2 in saturation,
// KP W / L (1 + LAMBDA vds) vds (vgs - VT - vds / 2) below it, VT = VTO + GAMMA (sqrt(PHI - vbs) -
// sqrt(PHI)). Nodes d g s b are unknowns 0-3; the drain row receives the current drawn into it.
TEST(DeviceLoad, MosfetDrainCurrentIsShichmanHodges) {
  const double kp = 50e-6, vto = 0.8, gamma = 0.5, phi = 0.65, lambda = 0.02, width = 20e-6, length = 2e-6;
  auto build = [&](double polarity) {
    CircuitSpec c;
    auto& m = c.add("m1", {"d", "g", "s", "b"}, polarity);
    m.model = {{"kp", kp}, {"vto", polarity * vto}, {"gamma", gamma}, {"phi", phi}, {"lambda", lambda}, {"is", 0}};
    m.instance_parameters = {{"w", width}, {"l", length}};
    return c;
  };
  const double beta = kp * width / length;
  auto threshold = [&](double vbs) { return vto + gamma * (std::sqrt(phi - vbs) - std::sqrt(phi)); };
  auto drain_current = [&](double vgs, double vds, double vbs) {
    const double overdrive = vgs - threshold(vbs);
    if (overdrive <= 0) return 0.0;
    if (overdrive <= vds) return beta * (1 + lambda * vds) * overdrive * overdrive / 2;
    return beta * (1 + lambda * vds) * vds * (overdrive - vds / 2);
  };
  Model nmos(build(1), {}), pmos(build(-1), {});
  auto current_into_drain = [](Model& model, double vd, double vg, double vs, double vb) {
    Vector x(4);
    x << vd, vg, vs, vb;
    const auto l = evaluate(model, 0, x, {});
    return l.f[0] + 1e-12 * (vb - vd);  // without the drain junction's gmin
  };
  struct Bias {
    double vd, vg, vs, vb;
  };
  for (const Bias b : {Bias{5, 3, 0, 0}, Bias{0.5, 3, 0, 0}, Bias{4, 2.5, 1, -1}, Bias{1.2, 4, 1, 0}, Bias{3, 0.5, 0, 0}}) {
    SCOPED_TRACE(::testing::Message() << "vd " << b.vd << " vg " << b.vg << " vs " << b.vs << " vb " << b.vb);
    const double expected = drain_current(b.vg - b.vs, b.vd - b.vs, b.vb - b.vs);
    EXPECT_NEAR(current_into_drain(nmos, b.vd, b.vg, b.vs, b.vb), expected, 1e-12 * std::abs(expected) + 1e-20);
    // PMOS: every voltage and the current mirrored.
    EXPECT_NEAR(current_into_drain(pmos, -b.vd, -b.vg, -b.vs, -b.vb), -expected, 1e-12 * std::abs(expected) + 1e-20);
    // Drain and source written the other way round: the same channel, the current reversed.
    EXPECT_NEAR(current_into_drain(nmos, b.vs, b.vg, b.vd, b.vb), -expected, 1e-12 * std::abs(expected) + 1e-20);
  }
}

// Bulk junctions (mos1load.c): IS (exp(v / vt) - 1) + gmin v above -3 vt, gmin v - IS below;
// the depletion charges of CBD and of CJSW times PD add.
TEST(DeviceLoad, MosfetBulkJunctionsAreNgspices) {
  CircuitSpec c;
  auto& m = c.add("m1", {"d", "g", "s", "b"}, 1);
  m.model = {{"is", 1e-13}, {"cbd", 1e-12}, {"cjsw", 1e-9}, {"pb", 0.9}, {"mj", 0.5}, {"mjsw", 0.33}, {"vto", 10}};
  m.instance_parameters = {{"pd", 4e-6}};
  Model model(c, {});
  Vector x(4);
  x << -0.5, 0, 0, 0.1;  // bulk-drain forward by 0.6 V, bulk-source by 0.1 V
  auto l = evaluate(model, 0, x, {});
  const double forward = 1e-13 * (std::exp(0.6 / thermal_voltage) - 1) + 1e-12 * 0.6;
  EXPECT_NEAR(l.f[0], -forward, 1e-12 * forward);
  x << 2.0, 0, 0, 0;  // drain junction reversed: -IS + gmin vbd
  l = evaluate(model, 0, x, {});
  EXPECT_NEAR(l.f[0], 1e-13 + 1e-12 * 2.0, 1e-26);
  const double side = 1e-9 * 4e-6;
  const double charge = 0.9 * 1e-12 * (1 - std::pow(1 + 2.0 / 0.9, 0.5)) / 0.5 +
                        0.9 * side * (1 - std::pow(1 + 2.0 / 0.9, 0.67)) / 0.67;
  EXPECT_NEAR(l.q[3], charge, 1e-9 * std::abs(charge));
}

TEST(DeviceLoad, NonFiniteValuesOrDerivativesAreOutsideTheDomain) {
  // B1: v(out) = atan2(v(in), 0) + sqrt(v(in)): atan2's slope is undefined at (0, 0), and sqrt
  // has no value below 0.
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 0.0);
  c.add("b1", {"out", "0"}).expression =
      binary(netlist::BinaryOperator::add, call("atan2", {voltage("in"), number(0)}), call("sqrt", {voltage("in")}));
  c.add("r1", {"out", "0"}, 1.0);
  Model m(c, {});
  padae::Load load;
  load.f = Vector::Zero(m.size()), load.q = Vector::Zero(m.size());
  load.df_dx.assign(m.pattern().nonzeros(), 0.0), load.dq_dx.assign(m.pattern().nonzeros(), 0.0);
  Vector x = Vector::Zero(m.size());
  load.jacobian_requested = false;
  EXPECT_EQ(m.load(0, x, {}, load), padae::EvalStatus::ok);
  load.jacobian_requested = true;
  EXPECT_EQ(m.load(0, x, {}, load), padae::EvalStatus::outside_domain);
  x[unknown(m, "v(in)")] = -1;
  load.f.setZero(), load.q.setZero();
  load.jacobian_requested = false;
  EXPECT_EQ(m.load(0, x, {}, load), padae::EvalStatus::outside_domain);
}

}  // namespace
}  // namespace mna::test
