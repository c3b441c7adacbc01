#!/usr/bin/env python3
"""padsim-versus-ngspice regression over circuits/ (cases and tolerances in cases.json).

    run_regression.py check-ngspice CASE...   ngspice at default settings completes to tstop
    run_regression.py floor [CASE...]         ngspice's own error: default and tight runs
                                              against a tighter one (--write floor.json)
    run_regression.py compare --padsim EXE CASE...
                                              padsim (defaults) against ngspice (tight)
    run_regression.py table                   README tables from floor.json
    run_regression.py list                    the cases

compare: both waveforms interpolated onto the reference's time points; per probe the max and
RMS of |padsim - ngspice| divided by the reference's range; switching instants (threshold
crossings of one signal) matched one to one and their time differences compared separately.
The max error has a time tolerance: ngspice's own switching-time error at default settings
(floor) plus the widest sampling step across a matched edge. Each reference point is compared
with the values padsim takes within that time of it (and each padsim point with the
reference's), so an edge displaced by no more than ngspice's own timing error costs nothing
there (the displacement is checked as a switching instant); the RMS has no time tolerance.
A case fails when an error exceeds its tolerance, when a crossing is missing or extra, or when
either simulator fails (ngspice can exit 0 after "Timestep too small": the last time point must
reach tstop).
"""
import argparse
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import spicecmp as sc  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(HERE))


def load_cases(path=os.path.join(HERE, "cases.json")):
    with open(path) as f:
        data = json.load(f)
    return {c["name"]: c for c in data["cases"]}


def netlist_of(case):
    return os.path.join(ROOT, "circuits", case["name"] + ".cir")


def tight_max_step(case):
    """The tight run's maximum step: 1e-5 of the simulated span unless the case says otherwise."""
    with open(netlist_of(case)) as f:
        tran = sc.parse_tran(f.read())
    return case.get("tight_max_step", (tran.stop - tran.start) / 1e5)


def tight_options(case):
    """ngspice options of the tight run; a case may override them (its comment says why)."""
    return case.get("tight_options", sc.TIGHT_OPTIONS)


def tighter_options(case):
    """One decade tighter than tight_options (reltol / 10), unless the case says otherwise."""
    if "tighter_options" in case:
        return case["tighter_options"]
    words = []
    for w in tight_options(case).split():
        if w.startswith("reltol="):
            w = "reltol=%g" % (float(w[7:]) / 10)
        words.append(w)
    return " ".join(words)


def padsim_arguments(args, case):
    """The padsim arguments of a case: the common ones (--padsim-args), with the case's
    padsim_rtol replacing their --rtol where the case says why, and its padsim_args added."""
    extra = args.padsim_args.split()
    if "padsim_rtol" in case:
        if "--rtol" in extra:
            extra[extra.index("--rtol") + 1] = str(case["padsim_rtol"])
        else:
            extra += ["--rtol", str(case["padsim_rtol"])]
    return extra + case.get("padsim_args", [])


def run_reference(case, workdir, level, ngspice):
    """level: 'default' (the netlist as written), 'tight' (the regression's reference) or
    'tighter' (used only to measure the tight run's own error)."""
    timeout = case.get("timeout", 300)
    if level == "default":
        return sc.run_ngspice(netlist_of(case), case["probes"], workdir, ngspice=ngspice,
                              tag="ngspice-default", timeout=timeout)
    if level == "tight":
        return sc.run_ngspice(netlist_of(case), case["probes"], workdir, options=tight_options(case),
                              max_step=tight_max_step(case), ngspice=ngspice, tag="ngspice-tight",
                              timeout=timeout)
    return sc.run_ngspice(netlist_of(case), case["probes"], workdir, options=tighter_options(case),
                          max_step=tight_max_step(case) / 4, ngspice=ngspice, tag="ngspice-tighter",
                          timeout=timeout)


def crossing_spec(case):
    """The case's switching-instant specification: a list of (probe, threshold, hysteresis)."""
    c = case.get("crossing")
    if c is None:
        return None
    return [(x["probe"], x["threshold"], x.get("hysteresis", 0.0)) for x in (c if isinstance(c, list) else [c])]


def measure(ref, test, case, tau=None):
    """Errors of test against ref for the case (switching instants from its crossing spec; tau:
    the max error's time tolerance, by default the measured switching-time difference)."""
    return sc.compare(ref, test, case["probes"], crossing_spec(case), tau)


def up(x, digits=2):
    """x rounded up to `digits` significant digits (tolerances are written readably)."""
    if x <= 0:
        return 0.0
    e = math.floor(math.log10(x)) - digits + 1
    return math.ceil(x / 10 ** e - 1e-9) * 10 ** e


# No tolerance below the resolution of the numbers compared: ngspice writes 12 significant
# digits (option numdgt=12), so relative differences under 1e-9 of the range are noise.
DATA_FLOOR = 1e-9


def tolerances(entry):
    """Tolerances of one case from its floor entry: twice ngspice's own error (default settings
    against the tight reference) plus twice the tight reference's own error (tight against
    tighter), per probe for max and RMS, and for the switching instants."""
    d, t = entry["default_vs_tight"], entry.get("tight_vs_tighter") or {}
    tp = t.get("probes", {})
    tol = {"probes": {}, "crossing_dt": None}
    for probe, (mx, rms) in d["probes"].items():
        tmx, trms = tp.get(probe, (0.0, 0.0))
        tol["probes"][probe] = (up(max(2 * (mx + tmx), DATA_FLOOR)), up(max(2 * (rms + trms), DATA_FLOOR)))
    if d.get("crossing"):
        tdt = (t.get("crossing") or {}).get("max_dt", 0.0)
        tol["crossing_dt"] = up(2 * (d["crossing"]["max_dt"] + tdt))
    # The max error's time tolerance: ngspice's own switching-time error at default settings.
    tol["tau"] = d["crossing"]["max_dt"] if d.get("crossing") else 0.0
    return tol


def load_floor(path=os.path.join(HERE, "floor.json")):
    with open(path) as f:
        return json.load(f)


def format_result(result):
    parts = []
    for probe, (mx, rms) in result["probes"].items():
        parts.append("%s max %.2e rms %.2e" % (probe, mx, rms))
    c = result["crossing"]
    if c:
        parts.append("crossings %d/%d max|dt| %.3g s" % (c["test_count"], c["ref_count"], c["max_dt"]))
    return "; ".join(parts)


def cmd_check_ngspice(args, cases):
    status = 0
    for name in args.cases:
        case = cases[name]
        try:
            w = run_reference(case, os.path.join(args.workdir, name), "default", args.ngspice)
            print("%-24s ok: %d points to t = %.6g s in %.2f s" % (name, len(w.time), w.time[-1], w.seconds))
        except sc.SimulationFailure as e:
            print("%-24s FAILED: %s" % (name, e))
            status = 1
    return status


def cmd_floor(args, cases):
    names = args.cases or [n for n, c in cases.items() if not c.get("padsim_only")]
    floor, status = {}, 0
    if args.write and os.path.exists(args.write):
        floor = load_floor(args.write)  # update the named cases, keep the others
    for name in names:
        case = cases[name]
        wd = os.path.join(args.workdir, name)
        try:
            default = run_reference(case, wd, "default", args.ngspice)
            tight = run_reference(case, wd, "tight", args.ngspice)
            tighter = run_reference(case, wd, "tighter", args.ngspice)
        except sc.SimulationFailure as e:
            print("%-24s FAILED: %s" % (name, e), flush=True)
            status = 1
            continue
        d = measure(tight, default, case)
        t = measure(tighter, tight, case)
        entry = {
            "default_vs_tight": d, "tight_vs_tighter": t,
            "seconds": {"default": round(default.seconds, 3), "tight": round(tight.seconds, 3),
                        "tighter": round(tighter.seconds, 3)},
            "points": {"default": len(default.time), "tight": len(tight.time), "tighter": len(tighter.time)},
            "ngspice_stats_default": default.stats,
            "tight_options": tight_options(case), "tight_max_step": tight_max_step(case),
        }
        entry["tolerance"] = tolerances(entry)
        floor[name] = entry
        print("%-24s default vs tight: %s" % (name, format_result(d)))
        print("%-24s tight vs tighter: %s" % ("", format_result(t)))
        print("%-24s time default %.2f s, tight %.2f s, tighter %.2f s" % (
            "", default.seconds, tight.seconds, tighter.seconds), flush=True)
    if args.write:
        with open(args.write, "w") as f:
            json.dump(floor, f, indent=1, sort_keys=True)
            f.write("\n")
    return status


def check_against(result, tol):
    """The list of tolerance violations of a padsim-versus-reference result."""
    failures = []
    for probe, (mx, rms) in result["probes"].items():
        tmx, trms = tol["probes"][probe]
        if mx > tmx:
            failures.append("%s max error %.3g > tolerance %.3g" % (probe, mx, tmx))
        if rms > trms:
            failures.append("%s RMS error %.3g > tolerance %.3g" % (probe, rms, trms))
    c = result["crossing"]
    if c:
        if c["unmatched"] or c["surplus"]:
            failures.append("switching instants: %d in ngspice, %d in padsim" % (c["ref_count"], c["test_count"]))
        if c["max_dt"] > tol["crossing_dt"]:
            failures.append("switching instant off by %.3g s > tolerance %.3g s" % (c["max_dt"], tol["crossing_dt"]))
    return failures


def summary_row(name, result, tol, test, default, ref, failures):
    """One markdown row: worst probe errors against their tolerances, switching instants, times."""
    worst = max(result["probes"].items(), key=lambda kv: kv[1][0] / max(tol["probes"][kv[0]][0], 1e-300))
    worst_rms = max(result["probes"].items(), key=lambda kv: kv[1][1] / max(tol["probes"][kv[0]][1], 1e-300))
    c = result["crossing"]
    sw = "-" if not c else "%d/%d, %.2g s (tol %.2g s)" % (c["test_count"], c["ref_count"], c["max_dt"], tol["crossing_dt"])
    return "| %s | %s | %s %.2g (tol %.2g) | %s %.2g (tol %.2g) | %s | %.3f | %.3f | %.3f |" % (
        name, "FAIL" if failures else "ok", worst[0], worst[1][0], tol["probes"][worst[0]][0],
        worst_rms[0], worst_rms[1][1], tol["probes"][worst_rms[0]][1], sw,
        test.seconds, default.seconds, ref.seconds)


def cmd_compare(args, cases):
    status = 0
    floor = load_floor(args.floor)
    rows = []
    for name in args.cases:
        case = cases[name]
        if name not in floor:
            print("%-24s FAILED: no floor measurement in %s (run: floor %s --write)" % (name, args.floor, name))
            status = 1
            continue
        tol = tolerances(floor[name])
        wd = os.path.join(args.workdir, name)
        try:
            ref = run_reference(case, wd, "tight", args.ngspice)
            default = run_reference(case, wd, "default", args.ngspice)
            test = sc.run_padsim(args.padsim, netlist_of(case), case["probes"], wd,
                                 extra=padsim_arguments(args, case))
        except sc.SimulationFailure as e:
            print("%-24s FAILED: %s" % (name, e))
            status = 1
            continue
        result = measure(ref, test, case, tol["tau"])
        failures = check_against(result, tol)
        rows.append(summary_row(name, result, tol, test, default, ref, failures))
        print("%-24s %s: %s" % (name, "FAILED" if failures else "ok", format_result(result)))
        print("%-24s time: padsim %.3f s, ngspice default %.3f s, ngspice tight %.3f s (%d/%d/%d points)"
              % ("", test.seconds, default.seconds, ref.seconds, len(test.time), len(default.time), len(ref.time)))
        for f in failures:
            print("%-24s   %s" % ("", f))
        if failures:
            status = 1
    if args.summary:
        with open(args.summary, "a") as f:
            for row in rows:
                f.write(row + "\n")
    return status


def cmd_padsim_only(args, cases):
    """Circuits ngspice cannot run: padsim must reach tstop with finite values and match the
    closed-form values listed under "expect" in cases.json."""
    status = 0
    for name in args.cases:
        case = cases[name]
        wd = os.path.join(args.workdir, name)
        try:
            w = sc.run_padsim(args.padsim, netlist_of(case), case["probes"], wd,
                              extra=padsim_arguments(args, case))
        except sc.SimulationFailure as e:
            print("%-24s FAILED: %s" % (name, e))
            status = 1
            continue
        failures = []
        for probe, ys in w.signals.items():
            if not all(math.isfinite(y) for y in ys):
                failures.append("%s has non-finite values" % probe)
        for e in case.get("expect", []):
            got = sc.interpolate(w.time, w.signals[e["probe"]], [e["time"]])[0]
            ok = abs(got - e["value"]) <= e["tolerance"]
            print("%-24s %s at t = %g: %.9g, expected %.9g +- %g (%s)" % (
                name, e["probe"], e["time"], got, e["value"], e["tolerance"], e.get("why", "")))
            if not ok:
                failures.append("%s at t = %g is %.9g, expected %.9g" % (e["probe"], e["time"], got, e["value"]))
        print("%-24s %s: %d points in %.3f s" % (name, "FAILED" if failures else "ok", len(w.time), w.seconds))
        for f in failures:
            print("%-24s   %s" % ("", f))
        if failures:
            status = 1
    return status


def cmd_table(args, cases):
    """README table of the floor measurements and the tolerances derived from them."""
    floor = load_floor(args.floor)
    print("| circuit | probe | ngspice default vs tight: max / RMS | tight vs tighter: max / RMS | tolerance max / RMS |")
    print("|---|---|---|---|---|")
    for name, case in cases.items():
        if name not in floor:
            continue
        e = floor[name]
        tol = tolerances(e)
        for k, probe in enumerate(case["probes"]):
            d = e["default_vs_tight"]["probes"][probe]
            t = e["tight_vs_tighter"]["probes"][probe]
            tp = tol["probes"][probe]
            print("| %s | %s | %.2g / %.2g | %.2g / %.2g | %.2g / %.2g |" % (
                name if k == 0 else "", probe, d[0], d[1], t[0], t[1], tp[0], tp[1]))
    print()
    print("| circuit | switching signal | crossings default/tight | ngspice default timing error | tight vs tighter | tolerance | ngspice time default / tight (s) |")
    print("|---|---|---|---|---|---|---|")
    for name, case in cases.items():
        if name not in floor:
            continue
        e = floor[name]
        tol = tolerances(e)
        c = e["default_vs_tight"]["crossing"]
        secs = "%.2f / %.2f" % (e["seconds"]["default"], e["seconds"]["tight"])
        if not c:
            print("| %s | - | - | - | - | - | %s |" % (name, secs))
            continue
        cs = ", ".join("%s at %g" % x[:2] for x in crossing_spec(case))
        print("| %s | %s | %d / %d | %.2g s | %.2g s | %.2g s | %s |" % (
            name, cs, c["test_count"], c["ref_count"], c["max_dt"],
            e["tight_vs_tighter"]["crossing"]["max_dt"], tol["crossing_dt"], secs))
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["check-ngspice", "floor", "compare", "padsim-only", "table", "list"])
    ap.add_argument("--ngspice-compatible", action="store_true", help="list: only the cases ngspice runs")
    ap.add_argument("--padsim-only", action="store_true", help="list: only the padsim-only cases")
    ap.add_argument("--known-failures", action="store_true",
                    help="list: only the cases padsim is known to fail (each with its reason in cases.json)")
    ap.add_argument("cases", nargs="*")
    ap.add_argument("--ngspice", default="ngspice")
    ap.add_argument("--padsim")
    ap.add_argument("--workdir", default=os.path.join(os.getcwd(), "ngspice-regression"))
    ap.add_argument("--write", help="floor: write (update) the measurements in this JSON file")
    ap.add_argument("--padsim-args", default="--grid --rtol 1e-6 --atol 1e-9",
                    help="compare, padsim-only: arguments for every padsim run (default: rows also on the "
                         ".tran TSTEP grid from padsim's interpolating polynomial, the output "
                         "resolution ngspice's default maximum step gives; and a tolerance at which padsim's "
                         "own error is well below the comparison's, since this checks that both simulators "
                         "converge to the same waveform; accuracy at default settings is the benchmark's)")
    ap.add_argument("--summary", help="compare: append one markdown table row per case to this file")
    ap.add_argument("--floor", default=os.path.join(HERE, "floor.json"), help="compare, table: the floor measurements")
    args = ap.parse_args(argv)
    cases = load_cases()
    for name in args.cases:
        if name not in cases:
            ap.error("unknown case %s (see: list)" % name)
    if args.mode == "list":
        for name, c in cases.items():
            if args.ngspice_compatible and c.get("padsim_only"):
                continue
            if args.padsim_only and not c.get("padsim_only"):
                continue
            if args.known_failures and not c.get("known_failure"):
                continue
            print(name)
        return 0
    if args.mode == "padsim-only":
        if not args.padsim:
            ap.error("padsim-only needs --padsim")
        return cmd_padsim_only(args, cases)
    if args.mode == "check-ngspice":
        return cmd_check_ngspice(args, cases)
    if args.mode == "floor":
        return cmd_floor(args, cases)
    if args.mode == "table":
        return cmd_table(args, cases)
    if not args.padsim:
        ap.error("compare needs --padsim")
    return cmd_compare(args, cases)


if __name__ == "__main__":
    sys.exit(main())
