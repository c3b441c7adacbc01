"""Unit tests of the comparison library (python3 -m unittest test_spicecmp)."""
import math
import os
import random
import shutil
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import spicecmp as sc  # noqa: E402
import run_regression as rr  # noqa: E402

NGSPICE = os.environ.get("PADSIM_NGSPICE", "ngspice")
ROOT = os.path.dirname(os.path.dirname(HERE))


def uneven_times(t_end, n, seed=1):
    """Sorted, non-uniform time points from 0 to t_end (like an adaptive integrator's)."""
    rng = random.Random(seed)
    steps = [0.2 + rng.random() for _ in range(n)]
    total = sum(steps)
    t, out = 0.0, [0.0]
    for s in steps:
        t += s * t_end / total
        out.append(t)
    out[-1] = t_end
    return out


class Numbers(unittest.TestCase):
    def test_suffixes(self):
        self.assertEqual(sc.spice_number("1k"), 1e3)
        self.assertEqual(sc.spice_number("10meg"), 10e6)
        self.assertEqual(sc.spice_number("10MEG"), 10e6)
        self.assertAlmostEqual(sc.spice_number("2.5u"), 2.5e-6, delta=1e-21)
        self.assertAlmostEqual(sc.spice_number("1m"), 1e-3, delta=1e-18)
        self.assertEqual(sc.spice_number("1e-3"), 1e-3)
        self.assertEqual(sc.spice_number("3.3v"), 3.3)
        self.assertAlmostEqual(sc.spice_number(".5n"), 0.5e-9, delta=1e-24)
        self.assertRaises(ValueError, sc.spice_number, "abc")

    def test_tran(self):
        text = "title\n* comment\nR1 a 0 1k\n.tran 1u\n+ 5m 0 10n uic\n.end\n"
        tran = sc.parse_tran(text)
        self.assertEqual((tran.step, tran.stop, tran.start, tran.max_step, tran.uic),
                         (1e-6, 5e-3, 0.0, 1e-8, True))
        self.assertRaises(ValueError, sc.parse_tran, "title\n.tran\n")
        self.assertRaises(ValueError, sc.parse_tran, "title\nR1 a 0 1\n")
        # The title line is never a card, even if it looks like one.
        self.assertEqual(sc.parse_tran(".tran 1 2\n.tran 1u 2u\n").stop, 2e-6)

    def test_deck(self):
        text = "t\nR1 a 0 1\n.tran 1u 1m uic\n.control\nrun\nplot v(a)\n.endc\n.end\n"
        deck = sc.ngspice_deck(text, ["v(a)", "i(v1)"], "/x/d.data", "reltol=1e-7", 1e-8)
        self.assertNotIn("plot", deck)
        self.assertIn(".tran 1e-06 0.001 0.0 1e-08 uic", deck)
        self.assertIn(".options reltol=1e-7", deck)
        for line in ["set wr_singlescale", "set wr_vecnames", "option numdgt=12", "run",
                     "wrdata /x/d.data v(a) i(v1)", "quit", ".endc", ".end"]:
            self.assertIn("\n" + line + "\n", deck)
        self.assertLess(deck.index("run\n"), deck.index("wrdata"))
        self.assertLess(deck.index("wrdata"), deck.index("quit"))


class Interpolation(unittest.TestCase):
    def test_linear_data_is_exact(self):
        t = uneven_times(1.0, 50)
        y = [3 * x - 1 for x in t]
        q = uneven_times(1.0, 77, seed=2)
        for a, b in zip(sc.interpolate(t, y, q), q):
            self.assertAlmostEqual(a, 3 * b - 1, places=12)

    def test_quadratic_error_bound(self):
        # Linear interpolation error of y = t^2 is at most h^2/4 * max|y''| / 2 = h^2 / 4.
        t = [k / 10 for k in range(11)]
        y = [x * x for x in t]
        q = [k / 1000 for k in range(1001)]
        worst = max(abs(a - b * b) for a, b in zip(sc.interpolate(t, y, q), q))
        self.assertLessEqual(worst, 0.1 ** 2 / 4 + 1e-15)
        self.assertGreater(worst, 0.1 ** 2 / 4 * 0.99)

    def test_jump_takes_right_limit_and_sides(self):
        # A jump at t = 1 recorded as two rows (left limit 0, right limit 5).
        t = [0.0, 1.0, 1.0, 2.0]
        y = [0.0, 0.0, 5.0, 5.0]
        got = sc.interpolate(t, y, [0.5, 0.999, 1.0, 1.001, 1.5])
        self.assertEqual(got, [0.0, 0.0, 5.0, 5.0, 5.0])

    def test_ends_are_held(self):
        self.assertEqual(sc.interpolate([1.0, 2.0], [3.0, 4.0], [0.0, 1.0, 2.0, 3.0]), [3.0, 3.0, 4.0, 4.0])


class ErrorMetrics(unittest.TestCase):
    def test_offset(self):
        t = uneven_times(1.0, 200)
        ref = [math.sin(2 * math.pi * x) for x in t]  # range 2
        test_t = uneven_times(1.0, 600, seed=5)
        test = [math.sin(2 * math.pi * x) + 0.01 for x in test_t]
        mx, rms = sc.waveform_error(t, ref, test_t, test)
        # interpolating the test data adds at most (2 pi)^2 h^2 / 8 = 1.4e-4 (h < 1.2 / (0.7 * 600)),
        # 7e-5 of the range
        self.assertAlmostEqual(mx, 0.005, delta=2e-4)
        self.assertAlmostEqual(rms, 0.005, delta=2e-4)

    def test_rms_is_time_weighted(self):
        # Difference 1 on [0, 0.1], 0 elsewhere; dense points in the first tenth must not inflate it.
        t = [k * 0.001 for k in range(101)] + [0.1 + k * 0.1 for k in range(1, 10)]
        ref = [0.0] * len(t)
        ref[-1] = 1.0  # range 1
        test = [(1.0 if x < 0.1 - 1e-12 else 0.0) for x in t]
        test[-1] = 1.0
        mx, rms = sc.waveform_error(t, ref, t, test)
        self.assertEqual(mx, 1.0)
        # integral of diff^2 over [0, 0.1] (trapezoid, last segment half) ~ 0.0995, over 1.0
        self.assertAlmostEqual(rms, math.sqrt(0.0995), delta=1e-3)

    def test_tube_distance(self):
        t = [k * 0.01 for k in range(101)]
        ref = [0.0 if x < 0.5 - 1e-9 else 1.0 for x in t]    # edge between 0.49 and 0.50
        test = [0.0 if x < 0.52 - 1e-9 else 1.0 for x in t]  # edge between 0.51 and 0.52
        self.assertEqual(max(sc.tube_distance(t, ref, t, test, 0.0)), 1.0)
        # The test reaches 1 at 0.52: within tau = 0.02 of the reference's 0.50, not of 0.49.
        self.assertEqual(max(sc.tube_distance(t, ref, t, test, 0.02)), 0.0)
        self.assertGreater(max(sc.tube_distance(t, ref, t, test, 0.015)), 0.0)
        # A ramp: the distance to the range of values within +-tau.
        d = sc.tube_distance([1.0], [5.0], [0.0, 2.0], [0.0, 2.0], 0.5)
        self.assertAlmostEqual(d[0], 3.5)  # the test spans [0.5, 1.5] around t = 1

    def test_jump_inside_a_reference_sampling_interval(self):
        # The test jumps from 1 to 0 at t = 0.5 (two rows); the reference samples 0.49 and 0.51,
        # so its linear interpolation at 0.5 is 0.5: the jump rows are compared with the
        # reference's values over that sampling interval, every other point as usual.
        t_ref = [k * 0.02 + 0.01 for k in range(50)]
        ref = [1.0 if x < 0.5 else 0.0 for x in t_ref]
        t_test = [k * 0.1 for k in range(6)] + [0.5] + [0.5 + k * 0.1 for k in range(1, 6)]
        test = [1.0] * 6 + [0.0] * 6
        slack = sc.jump_slack(t_test, t_ref)
        self.assertAlmostEqual(slack[5], 0.02)
        self.assertAlmostEqual(slack[6], 0.02)
        self.assertEqual(slack[4], 0.0)
        mx, _ = sc.waveform_error(t_ref, ref, t_test, test)
        self.assertEqual(mx, 0.0)
        # A spike elsewhere still counts in full.
        test[2] = 0.7
        mx, _ = sc.waveform_error(t_ref, ref, t_test, test)
        self.assertAlmostEqual(mx, 0.3)

    def test_time_tolerance_only_affects_max(self):
        t = [k * 0.01 for k in range(101)]
        ref = [0.0 if x < 0.5 - 1e-9 else 1.0 for x in t]
        test = [0.0 if x < 0.52 - 1e-9 else 1.0 for x in t]
        mx, rms = sc.waveform_error(t, ref, t, test)
        mx2, rms2 = sc.waveform_error(t, ref, t, test, 0.02)
        self.assertEqual((mx, mx2), (1.0, 0.0))
        self.assertEqual(rms, rms2)

    def test_compare_tau_from_crossings(self):
        t = [k * 0.01 for k in range(101)]
        ref = sc.Waveforms(t, {"v(s)": [0.0 if x < 0.5 - 1e-9 else 1.0 for x in t],
                               "v(r)": [0.0] * 100 + [1.0]})
        late = sc.Waveforms(t, {"v(s)": [0.0 if x < 0.52 - 1e-9 else 1.0 for x in t],
                                "v(r)": [0.0] * 100 + [1.0]})
        late.signals["v(r)"][30] = 0.25  # a spike in the test is never forgiven
        r = sc.compare(ref, late, ["v(s)", "v(r)"], [("v(s)", 0.5, 0.1)])
        self.assertAlmostEqual(r["crossing"]["max_dt"], 0.02)
        self.assertAlmostEqual(r["crossing"]["edge_step"], 0.01)  # the step across each edge
        self.assertAlmostEqual(r["tau"], 0.03)
        self.assertEqual(r["probes"]["v(s)"][0], 0.0)
        self.assertEqual(r["probes"]["v(r)"][0], 0.25)
        self.assertEqual((r["crossing"]["unmatched"], r["crossing"]["surplus"]), (0, 0))
        # With a smaller timing tolerance (ngspice's own, in the regression) the late edge shows.
        r = sc.compare(ref, late, ["v(s)"], [("v(s)", 0.5, 0.1)], tau=0.005)
        self.assertAlmostEqual(r["tau"], 0.015)
        # at t = 0.50 the reference is 1, the test at most 0.5 within +-0.015
        self.assertEqual(r["probes"]["v(s)"][0], 0.5)
        # A missing edge is reported.
        flat = sc.Waveforms(t, {"v(s)": [0.0] * 101})
        r = sc.compare(ref, flat, ["v(s)"], [("v(s)", 0.5, 0.1)])
        self.assertEqual(r["crossing"]["unmatched"], 1)
        self.assertEqual(r["probes"]["v(s)"][0], 1.0)

    def test_compare_uses_reference_range(self):
        ref = sc.Waveforms([0, 1, 2], {"v(a)": [0.0, 10.0, 0.0]})
        test = sc.Waveforms([0, 2], {"v(a)": [0.0, 0.0]})
        result = sc.compare(ref, test, ["V(A)"])
        self.assertEqual(result["probes"]["v(a)"][0], 1.0)


class Crossings(unittest.TestCase):
    def test_sine_zero_crossings_closed_form(self):
        f = 50.0
        t = uneven_times(0.1, 3000)
        y = [math.sin(2 * math.pi * f * x) for x in t]
        found = sc.crossings(t, y, 0.0, 0.1)
        # sin crosses 0 at k/(2f); the first (t = 0, from exactly 0) is not a crossing.
        expected = [(k / (2 * f), -1 if k % 2 else 1) for k in range(1, 10)]
        self.assertEqual([d for _, d in found], [d for _, d in expected])
        # Linear interpolation across a zero of sin: error O(h^3): tiny with h ~ 5e-5.
        for (tc, _), (te, _) in zip(found, expected):
            self.assertLess(abs(tc - te), 1e-9)

    def test_exponential_threshold_time(self):
        tau = 1e-3
        t = uneven_times(5e-3, 400)
        y = [1 - math.exp(-x / tau) for x in t]
        (tc, d), = sc.crossings(t, y, 0.5, 0.01)
        self.assertEqual(d, 1)
        h = max(b - a for a, b in zip(t, t[1:]))
        # linear interpolation error: h^2/8 |y''| / |y'| = h^2 / (8 tau) at the crossing
        self.assertLess(abs(tc - tau * math.log(2)), h * h / (8 * tau) + 1e-15)

    def test_hysteresis_rejects_chatter(self):
        # A falling edge at 1.0 with ringing around the threshold after it.
        t = [0.0, 0.99, 1.0, 1.01, 1.02, 1.03, 1.04, 2.0]
        y = [1.0, 1.0, 0.55, 0.45, 0.52, 0.48, 0.0, 0.0]
        self.assertEqual(len(sc.crossings(t, y, 0.5, 0.0)), 3)  # down, up, down
        found = sc.crossings(t, y, 0.5, 0.1)
        self.assertEqual(len(found), 1)
        self.assertEqual(found[0][1], -1)
        self.assertAlmostEqual(found[0][0], 1.025, places=12)  # last passage before leaving the band

    def test_vertical_jump(self):
        t = [0.0, 1.0, 1.0, 2.0]
        y = [0.0, 0.0, 5.0, 5.0]
        self.assertEqual(sc.crossings(t, y, 2.5), [(1.0, 1)])
        self.assertEqual(sc.crossing_brackets(t, y, 2.5), [(1.0, 1, 1.0, 1.0)])

    def test_matching(self):
        ref = [(1.0, 1), (2.0, -1), (3.0, 1)]
        test = [(1.1, 1), (1.95, -1), (3.0, 1)]
        mx, pairs, unmatched, surplus = sc.match_crossings(ref, test)
        self.assertAlmostEqual(mx, 0.1)
        self.assertEqual(pairs, [(0, 0), (1, 1), (2, 2)])
        self.assertEqual((unmatched, surplus), (0, 0))
        mx, pairs, unmatched, surplus = sc.match_crossings(ref, test[:2] + [(3.5, -1), (4.0, 1)])
        self.assertEqual(unmatched, 0)
        self.assertEqual(surplus, 1)
        self.assertEqual(sc.match_crossings(ref, test[:1])[2], 2)


class Tolerances(unittest.TestCase):
    def test_up(self):
        self.assertEqual(rr.up(1.234e-5), 1.3e-5)
        self.assertEqual(rr.up(1.2e-5), 1.2e-5)
        self.assertEqual(rr.up(0.0), 0.0)

    def test_derivation(self):
        entry = {"default_vs_tight": {"probes": {"v(a)": [1e-4, 1e-5]}, "crossing": {"max_dt": 2e-9}},
                 "tight_vs_tighter": {"probes": {"v(a)": [1e-6, 1e-7]}, "crossing": {"max_dt": 1e-11}}}
        tol = rr.tolerances(entry)
        self.assertAlmostEqual(tol["probes"]["v(a)"][0], 2.1e-4)
        self.assertAlmostEqual(tol["probes"]["v(a)"][1], 2.1e-5)
        self.assertAlmostEqual(tol["crossing_dt"], 4.1e-9)
        self.assertEqual(tol["tau"], 2e-9)  # ngspice's own timing error, not the doubled tolerance
        fails = rr.check_against({"probes": {"v(a)": (3e-4, 1e-6)},
                                  "crossing": {"max_dt": 1e-9, "unmatched": 0, "surplus": 1,
                                               "ref_count": 3, "test_count": 4}}, tol)
        self.assertEqual(len(fails), 2)

    def test_every_regression_case_has_a_floor(self):
        cases = rr.load_cases()
        floor = rr.load_floor()
        compatible = [n for n, c in cases.items() if not c.get("padsim_only")]
        self.assertGreaterEqual(len(compatible), 15)
        for name in compatible:
            self.assertIn(name, floor, "run: run_regression.py floor %s --write floor.json" % name)
            self.assertTrue(os.path.exists(rr.netlist_of(cases[name])))
            for probe in cases[name]["probes"]:
                self.assertIn(probe, floor[name]["default_vs_tight"]["probes"])


class CircuitLibrary(unittest.TestCase):
    """circuits/: every netlist says what it shows, what to look at, and where it runs; the
    regression covers every ngspice-compatible one."""

    def test_headers_and_coverage(self):
        cases = rr.load_cases()
        folder = os.path.join(ROOT, "circuits")
        netlists = sorted(f[:-4] for f in os.listdir(folder) if f.endswith(".cir"))
        self.assertGreaterEqual(len(netlists), 20)
        for name in netlists:
            with open(os.path.join(folder, name + ".cir")) as f:
                text = f.read()
            header = []
            for line in text.splitlines():
                if not line.startswith("*"):
                    break
                header.append(line)
            header = "\n".join(header)
            self.assertIn("Shows:", header, name)
            self.assertIn("Look at:", header, name)
            ngspice_ok = "Runs in ngspice unchanged" in header
            padsim_only = "padsim only" in header
            self.assertTrue(ngspice_ok != padsim_only, "%s: say either 'Runs in ngspice unchanged' or 'padsim only'" % name)
            self.assertIn(name, cases, "%s is not in tests/ngspice/cases.json" % name)
            self.assertEqual(bool(cases[name].get("padsim_only")), padsim_only, name)
            sc.parse_tran(text)

    def test_ladder_generator(self):
        import subprocess
        gen = os.path.join(ROOT, "circuits", "gen_rc_ladder.py")
        out = subprocess.run([sys.executable, gen, "100"], stdout=subprocess.PIPE, check=True).stdout.decode()
        with open(os.path.join(ROOT, "circuits", "rc_ladder_100.cir")) as f:
            self.assertEqual(out, f.read(), "rc_ladder_100.cir is the generator's output for N = 100")
        big = subprocess.run([sys.executable, gen, "100000", "--ideal"], stdout=subprocess.PIPE,
                             check=True).stdout.decode()
        cards = sc.logical_lines(big)
        self.assertEqual(sum(1 for c in cards if c[0] in "Rr"), 100000)
        self.assertEqual(sum(1 for c in cards if c[0] in "Cc"), 100000)
        self.assertEqual(sum(1 for c in cards if c[0] in "Ss"), 10000)
        self.assertIn("ron=0 ", big)
        self.assertIn("padsim only", big.splitlines()[3])
        self.assertGreater(sc.parse_tran(big).stop, 0)


class Files(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="spicecmp-")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def test_csv_quoted_names_and_cut_last_line(self):
        path = os.path.join(self.dir, "x.csv")
        with open(path, "w") as f:
            f.write('time,"v(a,b)",i(l1)\n0,1,2\n1e-6,3,4\n2e-6,5')  # killed mid-line
        names, cols = sc.read_csv(path)
        self.assertEqual(names, ["time", "v(a,b)", "i(l1)"])
        self.assertEqual(cols[0], [0.0, 1e-6])

    def test_reached_tstop(self):
        sc.check_reached_tstop([0.0, 1e-3], 1e-3)
        self.assertRaises(sc.SimulationFailure, sc.check_reached_tstop, [0.0, 0.5e-3], 1e-3)
        self.assertRaises(sc.SimulationFailure, sc.check_reached_tstop, [], 1e-3)

    def test_log_scan(self):
        self.assertIsNone(sc.scan_ngspice_log("Circuit: x\nngspice-39 done\n"))
        self.assertIn("Timestep too small",
                      sc.scan_ngspice_log("a\ndoAnalyses: TRAN:  Timestep too small; time = 1e-6\nb"))
        self.assertIsNotNone(sc.scan_ngspice_log("tran simulation(s) aborted"))
        self.assertIsNotNone(sc.scan_ngspice_log("Warning: singular matrix:  check node x"))


@unittest.skipUnless(shutil.which(NGSPICE), "ngspice is not installed")
class NgspiceRuns(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="spicecmp-ng-")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def test_failing_deck_is_caught(self):
        # ngspice prints "Timestep too small" at t = 5 us, exits 0, and writes data up to 5 us.
        deck = os.path.join(HERE, "data", "fails_mid_transient.cir")
        with self.assertRaises(sc.SimulationFailure) as ctx:
            sc.run_ngspice(deck, ["v(out)"], self.dir, ngspice=NGSPICE)
        self.assertIn("timestep too small", str(ctx.exception).lower())
        # Even without the message, the data stops short of tstop.
        names, cols = sc.read_wrdata(os.path.join(self.dir, "ngspice.data"))
        self.assertRaises(sc.SimulationFailure, sc.check_reached_tstop, cols[0], 20e-6)

    def test_silent_short_run_is_caught(self):
        deck = os.path.join(HERE, "data", "fails_mid_transient.cir")
        fake = os.path.join(HERE, "data", "fake_ngspice.py")
        with self.assertRaises(sc.SimulationFailure) as ctx:
            sc.run_ngspice(deck, ["v(out)"], self.dir, ngspice=fake)
        self.assertIn("before tstop", str(ctx.exception))

    def compare_with_fake_padsim(self, case, **env):
        fake = os.path.join(HERE, "data", "fake_padsim.py")
        saved = dict(os.environ)
        os.environ.update({k: str(v) for k, v in env.items()})
        try:
            return rr.main(["compare", case, "--padsim", fake, "--padsim-args", "",
                            "--ngspice", NGSPICE, "--workdir", self.dir])
        finally:
            os.environ.clear()
            os.environ.update(saved)

    def test_compare_accepts_ngspice_default_and_rejects_perturbations(self):
        # The whole compare path with its floor-derived tolerances: ngspice's own default answer
        # passes (it is the floor's "default"), a 1 % gain error or a 20 us delay does not.
        self.assertEqual(self.compare_with_fake_padsim("rc_step"), 0)
        self.assertEqual(self.compare_with_fake_padsim("rc_step", FAKE_PADSIM_SCALE=1.01), 1)
        self.assertEqual(self.compare_with_fake_padsim("rc_step", FAKE_PADSIM_DELAY=20e-6), 1)
        # A switching circuit: the comparator edges of the relaxation oscillator.
        self.assertEqual(self.compare_with_fake_padsim("relaxation_oscillator"), 0)
        self.assertEqual(self.compare_with_fake_padsim("relaxation_oscillator", FAKE_PADSIM_DELAY=20e-6), 1)

    def test_rc_step_against_closed_form(self):
        # The whole ngspice path (deck, wrdata, parsing, interpolation) against 1 - exp(-t/tau).
        w = sc.run_ngspice(os.path.join(ROOT, "circuits", "rc_step.cir"), ["v(out)"], self.dir,
                           options=sc.TIGHT_OPTIONS, max_step=5e-8, ngspice=NGSPICE)
        t = [k * 1e-5 for k in range(501)]
        exact = [0.0 if x <= 100e-6 else 1 - math.exp(-(x - 100e-6) / 1e-3) for x in t]
        got = sc.interpolate(w.time, w.signals["v(out)"], t)
        worst = max(abs(a - b) for a, b in zip(got, exact))
        self.assertLess(worst, 1e-5)  # the 1 ns source edge alone accounts for ~1e-6
        (tc, d), = sc.crossings(w.time, w.signals["v(out)"], 0.5, 0.01)
        self.assertAlmostEqual(tc, 100e-6 + 0.5e-9 + 1e-3 * math.log(2), delta=2e-9)


if __name__ == "__main__":
    unittest.main()
