"""Unit tests of the report's pure helpers (CTest: bench.report_helpers, in builds with
-DPADSIM_BENCH=ON). Each closed form is checked against an independent property: a textbook
value, continuity, or the circuit's own differential equation."""
import math
import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import report_lib as rl  # noqa: E402
import spicecmp as sc  # noqa: E402


class ClosedForms(unittest.TestCase):
    def test_rlc_overshoot_is_the_textbook_value(self):
        # Step response peak at pi / wd after the edge: 1 + exp(-alpha pi / wd). The 1 ns ramp
        # shifts it by half the rise.
        r = rl.RlcStep()
        self.assertAlmostEqual(r.alpha, 5000.0)
        self.assertAlmostEqual(r.wd, math.sqrt(1e9 - 2.5e7), places=6)
        t_peak = r.delay + 0.5 * r.rise + math.pi / r.wd
        self.assertAlmostEqual(r(t_peak)["v(out)"], 1 + math.exp(-5000 * math.pi / r.wd), places=10)
        self.assertAlmostEqual(r(t_peak)["v(out)"], 1.60468, places=5)
        # At the peak the capacitor current is zero; before the edge everything is at rest.
        self.assertLess(abs(r(t_peak)["i(l1)"]), 1e-10)
        self.assertEqual(r(r.delay)["v(out)"], 0.0)

    def test_rlc_satisfies_its_equations(self):
        # i = C dv/dt, and L di/dt = 1 - R i - v after the edge.
        r = rl.RlcStep()
        t, h = 0.3e-3, 1e-9
        dv = (r(t + h)["v(out)"] - r(t - h)["v(out)"]) / (2 * h)
        di = (r(t + h)["i(l1)"] - r(t - h)["i(l1)"]) / (2 * h)
        v, i = r(t)["v(out)"], r(t)["i(l1)"]
        self.assertAlmostEqual(r.c * dv, i, delta=1e-9)
        self.assertAlmostEqual(r.l * di, 1 - r.r * i - v, delta=1e-7)

    def test_relaxation_oscillator_edges_and_continuity(self):
        ro = rl.RelaxationOscillator()
        self.assertAlmostEqual(ro.t1, 1e-3 * math.log(3.2), places=15)   # 1.1632 ms
        self.assertAlmostEqual(ro.half_period, 1.0986122886681098e-3, places=15)
        edges = ro.edges(10e-3)
        self.assertEqual(len(edges), 9)
        self.assertEqual([d for _, d in edges[:3]], [1, -1, 1])
        for t, d in edges:
            before, after = ro(t * (1 - 1e-12)), ro(t * (1 + 1e-12))
            self.assertAlmostEqual(before["v(cap)"], after["v(cap)"], places=7)   # the capacitor is continuous
            self.assertAlmostEqual(abs(before["v(cap)"]), 2.5, places=7)          # edges at the thresholds
            self.assertEqual(after["v(out)"], 5.0 * d)

    def test_stiff_cascade_first_stage_and_ode(self):
        s = rl.StiffCascade()
        # First stage after the ramp: 1 - (tau / rise) (1 - exp(-rise / tau)) exp(-(t - rise) / tau).
        self.assertAlmostEqual(s.stage(0, 2e-9), 1 - math.exp(-1) * (1 - math.exp(-1)), places=12)
        # Continuous where the closed form switches branch (end of the rise).
        self.assertAlmostEqual(s.stage(1, 1e-9 * (1 - 1e-9)), s.stage(1, 1e-9 * (1 + 1e-9)), places=9)
        # Stage k follows tau_k dv_k/dt = v_{k-1} - v_k.
        for k, t in ((1, 2e-6), (2, 1.5e-3), (3, 0.7)):
            h = 1e-4 * s.taus[k]
            dv = (s.stage(k, t + h) - s.stage(k, t - h)) / (2 * h)
            self.assertAlmostEqual(s.taus[k] * dv, s.stage(k - 1, t) - s.stage(k, t), delta=1e-7)
        # The slowest stage: 99.3 % at 5 s.
        self.assertAlmostEqual(s.stage(3, 5.0), 0.99326, places=5)

    def test_exact_crossings_refine_to_the_closed_form(self):
        ro = rl.RelaxationOscillator()
        grid = rl.uniform_grid(0, 10e-3, 2001)
        found = rl.exact_crossings(ro, "v(out)", 0.0, 1.0, grid)
        self.assertEqual(len(found), 9)
        for (t, d), (te, de) in zip(found, ro.edges(10e-3)):
            self.assertEqual(d, de)
            self.assertLess(abs(t - te), 1e-15)

    def test_bari_error(self):
        self.assertEqual(rl.bari_error(rl.BARI_TRANSAMP), 0.0)
        values = list(rl.BARI_TRANSAMP)
        values[7] += 1e-6
        self.assertAlmostEqual(rl.bari_error(values), 1e-6 / (1 + 1.236995868091548), delta=1e-15)


class Metrics(unittest.TestCase):
    def test_pointwise_error(self):
        t = [0.0, 1.0, 2.0, 3.0]
        mx, rms = rl.pointwise_error(t, [0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 2.0, 2.0], 2.0)
        self.assertAlmostEqual(mx, 0.5)
        # |diff| = 0, 0, 0, 1: trapezoid of diff^2 = 0.5 over 3 s.
        self.assertAlmostEqual(rms, math.sqrt(0.5 / 3) / 2.0)

    def test_closed_form_reference_scales_by_range(self):
        ro = rl.RelaxationOscillator()
        ref = rl.ClosedFormReference(ro, ["v(cap)"], rl.uniform_grid(0, 10e-3, 20001))
        # From 3 V down to -2.5 V (the grid's samples come within 0.2 mV of the thresholds).
        self.assertAlmostEqual(ref.scale["v(cap)"], 5.5, delta=2e-4)
        times = rl.uniform_grid(0, 10e-3, 101)
        test = sc.Waveforms(times, {"v(cap)": [ro(t)["v(cap)"] + 0.011 for t in times]})
        mx, rms = ref.errors(test)["v(cap)"]
        self.assertAlmostEqual(mx, 0.011 / ref.scale["v(cap)"], places=12)
        self.assertAlmostEqual(rms, 0.011 / ref.scale["v(cap)"], places=12)

    def test_match_crossings(self):
        ref = [(1.0, 1), (2.0, -1), (3.0, 1)]
        test = [(1.1, 1), (2.05, -1), (2.2, -1), (2.9, 1)]
        dts, rel, unmatched, surplus = rl.match_crossings(ref, test)
        self.assertEqual(unmatched, 0)
        self.assertEqual(surplus, 1)
        self.assertAlmostEqual(max(dts), 0.1)
        self.assertAlmostEqual(max(rel), 0.1)
        dts, rel, unmatched, surplus = rl.match_crossings(ref, [(1.0, 1)])
        self.assertEqual((unmatched, surplus), (2, 0))


class WorkPrecision(unittest.TestCase):
    def test_pareto_front_drops_dominated_runs(self):
        pts = [(1e-2, 1.0), (1e-3, 2.0), (2e-2, 3.0), (1e-4, 4.0), (0.0, 0.5)]
        self.assertEqual(rl.pareto_front(pts), [(1e-2, 1.0), (1e-3, 2.0), (1e-4, 4.0)])

    def test_time_at_error_interpolates_log_log(self):
        front = [(1e-2, 1.0), (1e-4, 4.0)]
        self.assertAlmostEqual(rl.time_at_error(front, 1e-3), 2.0)  # half-way in log: sqrt(1 * 4)
        self.assertEqual(rl.time_at_error(front, 1e-1), 1.0)
        self.assertIsNone(rl.time_at_error(front, 1e-5))

    def test_ratios_on_the_common_error_range(self):
        a = [(1e-1, 0.01), (1e-3, 0.02), (1e-6, 0.04)]
        b = [(1e-2, 1.0), (1e-4, 4.0)]
        r = rl.ratios_at_equal_error(a, b)
        # a's errors down to b's best (1e-4): at 1e-1 b needs its fastest run.
        self.assertEqual([x[0] for x in r], [1e-1, 1e-3, 1e-4])
        self.assertAlmostEqual(r[0][3], 0.01 / 1.0)
        self.assertAlmostEqual(r[1][3], 0.02 / 2.0)
        self.assertAlmostEqual(r[2][3], 0.02 * 2 ** (1 / 3) / 4.0)  # a at 1e-4: a third of the way in log
        # b's only run beats anything a does: at every error of a, b needs that run.
        r = rl.ratios_at_equal_error(a, [(1e-8, 1.0)])
        self.assertEqual([x[0] for x in r], [1e-1, 1e-3, 1e-6])
        for x, expected in zip(r, (0.01, 0.02, 0.04)):
            self.assertAlmostEqual(x[3], expected)
        r = rl.ratios_at_equal_error([(1e-8, 1.0)], a)
        self.assertEqual(len(r), 1)
        self.assertEqual(r[0][0], 1e-6)
        self.assertAlmostEqual(r[0][3], 25.0)

    def test_loglog_slope_and_median(self):
        self.assertAlmostEqual(rl.loglog_slope([1, 10, 100], [2, 20, 200]), 1.0)
        self.assertAlmostEqual(rl.loglog_slope([1, 10, 100], [1, 100, 10000]), 2.0)
        self.assertEqual(rl.median([3, 1, 2]), 2)
        self.assertEqual(rl.vntol_for(1e-2), 1e-6)
        self.assertAlmostEqual(rl.vntol_for(1e-7), 1e-10)


if __name__ == "__main__":
    unittest.main()
