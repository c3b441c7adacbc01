#!/usr/bin/env python3
"""padsim's robustness suite: stiff and extreme circuits, events, faults and bad input.

Every case runs the padsim command on a netlist of this directory and checks numbers against a
closed form, a physical invariant or ngspice's run of the same netlist (cases/*.cir), or the
exact diagnostic and exit code 2 (invalid/*.cir). Python 3 standard library only, and
tests/ngspice/spicecmp.py for ngspice.

    robustness.py list [--known-failures]            the case names (CTest registers one test each)
    robustness.py run CASE --padsim PADSIM           one case: its criteria and figures; exit 1 if any fails
    robustness.py report --padsim PADSIM --output docs/robustness.md
                                                     every case (known failures too), as a Markdown page

Cases padsim is known to fail stay in the suite with their reason (KNOWN_FAILURES below): CTest
lists them as disabled, the report shows what they measure. Remove the entry when a case passes.
"""

import argparse
import cmath
import csv
import io
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "ngspice"))
import spicecmp  # noqa: E402  (ngspice runs: the references of a few cases)
REPO = HERE.parent.parent
CASES_DIR = HERE / "cases"
BAD_DIR = HERE / "invalid"  # the netlist corpus test skips directories named invalid
DEFAULT_RTOL = spicecmp.PADSIM_DEFAULT_RTOL

# Cases padsim fails today, with the reason (shown in CTest as disabled and in the report).
KNOWN_FAILURES = {}

BAD_INPUT_SECONDS = 10  # a refusal takes milliseconds; 10 s leaves room for the sanitizer build
SANITIZER_MARKS = ("AddressSanitizer", "LeakSanitizer", "UndefinedBehaviorSanitizer", "runtime error:")


# --- running padsim -------------------------------------------------------------------------------

class Run:
    """One padsim run: exit status, output text, CSV rows, --stats, --events."""

    def __init__(self, command, returncode, stdout, stderr, wall, csv_path=None, events_path=None):
        self.command = command
        self.returncode = returncode  # negative: killed by that signal
        self.stdout = stdout
        self.stderr = stderr
        self.wall = wall
        self.header, self.rows = [], []
        if csv_path and Path(csv_path).exists():
            self.header, self.rows = read_csv(csv_path)
        self.events = []
        if events_path and Path(events_path).exists():
            with open(events_path, newline="") as f:
                for row in csv.DictReader(f):
                    row["time"] = float(row["time"])
                    row["jump_energy"] = float(row["jump_energy"])
                    self.events.append(row)
        self.stats = None
        for line in stderr.splitlines():
            if line.startswith("{") and '"steps"' in line:
                self.stats = json.loads(line)

    def column(self, name):
        k = self.header.index(name)
        return [row[k] for row in self.rows]

    def times(self):
        return [row[0] for row in self.rows]

    def failure_time(self):
        m = re.search(r"simulation failed at t = ([-+0-9.eE]+) s", self.stderr)
        return float(m.group(1)) if m else None

    def error_text(self):
        return " ".join(line for line in self.stderr.splitlines() if "error:" in line)

    def sanitizer_report(self):
        return any(mark in self.stderr for mark in SANITIZER_MARKS)


def read_csv(path):
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader, [])
        rows = [[float(x) if x != "" else math.nan for x in row] for row in reader]
    return header, rows


def describe_status(code):
    if code is None:
        return "timed out"
    if code < 0:
        return "killed by " + signal.Signals(-code).name
    return f"exit {code}"


# --- closed forms ---------------------------------------------------------------------------------

def lag_coefficient(taus, j):
    a = 1.0
    for i, ti in enumerate(taus):
        if i != j:
            a *= taus[j] / (taus[j] - ti)
    return a


def lag_response(taus, t, t0, rise):
    """The unity-gain cascade prod_j 1 / (1 + s tau_j) driven by a 0 -> 1 ramp over [t0, t0 + rise]
    (a step if rise = 0), from rest."""
    u = t - t0
    if u <= 0:
        return 0.0
    if rise == 0 or u >= rise:
        s = 0.0
        for j, tj in enumerate(taus):
            if rise == 0:
                f = math.exp(-u / tj)
            else:  # the ramp's step responses, combined without overflow
                f = math.exp(-(u - rise) / tj) * (tj / rise) * (-math.expm1(-rise / tj))
            s += lag_coefficient(taus, j) * f
        return 1 - s
    s = u
    for j, tj in enumerate(taus):
        s -= lag_coefficient(taus, j) * tj * (-math.expm1(-u / tj))
    return s / rise


def affine2(a, b, x0, t):
    """x(t) for x' = A x + b (2 x 2, A invertible) from x(0) = x0: the particular solution plus
    exp(A t) applied to the rest (exp of a 2 x 2 matrix in closed form)."""
    (a11, a12), (a21, a22) = a
    det = a11 * a22 - a12 * a21
    xp = [-(a22 * b[0] - a12 * b[1]) / det, -(-a21 * b[0] + a11 * b[1]) / det]
    y = [x0[0] - xp[0], x0[1] - xp[1]]
    s = (a11 + a22) / 2
    q = cmath.sqrt(s * s - det)
    c = cmath.cosh(q * t)
    sh = cmath.sinh(q * t) / q if abs(q) > 1e-300 else t
    e = cmath.exp(s * t)
    m11, m12 = e * (c + sh * (a11 - s)), e * sh * a12
    m21, m22 = e * sh * a21, e * (c + sh * (a22 - s))
    return [xp[0] + (m11 * y[0] + m12 * y[1]).real, xp[1] + (m21 * y[0] + m22 * y[1]).real]


def bisect(f, lo, hi, iterations=200):
    flo = f(lo)
    for _ in range(iterations):
        mid = (lo + hi) / 2
        fm = f(mid)
        if (fm > 0) == (flo > 0):
            lo, flo = mid, fm
        else:
            hi = mid
        if hi - lo <= 4 * math.ulp(hi):
            break
    return (lo + hi) / 2


def ngspice_reference(c, probes, options, max_step):
    """ngspice's run of the case's netlist, its own .options cards replaced by options (spicecmp
    Waveforms), or None after a failed criterion that says why."""
    text = "".join(line for line in c.netlist.read_text().splitlines(keepends=True)
                   if not line.lower().startswith(".options"))
    netlist = c.workdir / "ngspice-reference.cir"
    netlist.write_text(text)
    c.commands.append(f"ngspice -b (netlist without its .options; .options {options}, max step {g(max_step)} s)")
    try:
        return spicecmp.run_ngspice(str(netlist), probes, str(c.workdir), options=options, max_step=max_step)
    except spicecmp.SimulationFailure as failure:
        c.expect(False, f"ngspice's reference run: {failure}")
        return None


def difference_from(reference, run, column, t_from=0.0):
    """(the largest |run - reference| in column over the run's rows from t_from on, the reference
    interpolated linearly onto them; the instant where it is)."""
    k = run.header.index(column)
    rows = [row for row in run.rows if row[0] >= t_from]
    values = spicecmp.interpolate(reference.time, reference.signals[column], [row[0] for row in rows])
    worst, at = 0.0, None
    for row, value in zip(rows, values):
        e = abs(row[k] - value)
        if not e <= worst:  # NaN counts as the worst
            worst, at = e if e == e else math.inf, row[0]
    return worst, at


def max_error(run, column, exact, keep=lambda t: True):
    """(largest |padsim - exact| over the rows, the time where it is)."""
    k = run.header.index(column)
    worst, at = 0.0, None
    for row in run.rows:
        t = row[0]
        if not keep(t):
            continue
        e = abs(row[k] - exact(t))
        if not e <= worst:  # NaN counts as the worst
            worst, at = e if e == e else math.inf, t
    return worst, at


# --- a case's context -----------------------------------------------------------------------------

def g(x):
    """A number for the report: 3 significant digits."""
    if x is None:
        return "-"
    if isinstance(x, int):
        return str(x)
    return f"{x:.3g}"


class Context:
    def __init__(self, name, padsim, workdir, full):
        self.name = name
        self.padsim = str(padsim)
        self.workdir = Path(workdir) / name
        self.workdir.mkdir(parents=True, exist_ok=True)
        self.full = full  # report mode: extra, informative runs
        self.criteria = []  # (passed, text)
        self.key = []       # the criteria the report's summary shows
        self.figures = []   # text
        self.commands = []
        self.netlist = CASES_DIR / f"{name}.cir"

    def expect(self, passed, text, key=False):
        self.criteria.append((bool(passed), text))
        if key:
            self.key.append(text)
        return bool(passed)

    def figure(self, text):
        self.figures.append(text)

    def stats_figure(self, run, label=""):
        s = run.stats
        if not s:
            return
        self.figure(f"{label}steps {s.get('steps')}, rejected {s.get('rejected')} (error test {s.get('rejected_error_test')}, "
                    f"Newton {s.get('rejected_newton')}, domain {s.get('rejected_domain')}), events {s.get('events')}, "
                    f"jumps {s.get('jumps')}, wall {s.get('wall_s', 0):.3f} s")

    def run(self, netlist=None, args=(), tag="run", events=False, csv_out=True, cwd=None, timeout=900, quiet=True):
        netlist = str(netlist or self.netlist)
        csv_path = self.workdir / f"{tag}.csv"
        events_path = self.workdir / f"{tag}.events.csv"
        for p in (csv_path, events_path):
            if p.exists():
                p.unlink()
        command = [self.padsim, netlist, "--stats"] + (["-q"] if quiet else [])
        if csv_out:
            command += ["-o", str(csv_path)]
        if events:
            command += ["--events", str(events_path)]
        command += list(args)
        self.commands.append(display_command(command, self.workdir, cwd))
        start = time.monotonic()
        try:
            p = subprocess.run(command, capture_output=True, text=True, encoding="utf-8", errors="replace",
                               cwd=cwd, timeout=timeout, preexec_fn=lambda: signal.alarm(int(timeout) + 60))
            code, out, err = p.returncode, p.stdout, p.stderr
        except subprocess.TimeoutExpired as e:
            code, out, err = None, "", (e.stderr or b"").decode(errors="replace") if isinstance(e.stderr, bytes) else (e.stderr or "")
        run = Run(command, code, out, err, time.monotonic() - start,
                  csv_path if csv_out else None, events_path if events else None)
        self.expect(not run.sanitizer_report(), "no sanitizer report")
        return run


def display_command(command, workdir, cwd):
    """The command as a user would type it from the repository root."""
    parts = []
    for i, c in enumerate(command):
        c = str(c)
        if i == 0:
            c = "padsim"
        elif c.startswith(str(workdir)):
            c = "out/" + Path(c).name
        elif c.startswith(str(REPO) + "/"):
            c = os.path.relpath(c, REPO)
        elif cwd and i == 1:
            c = os.path.relpath(Path(cwd) / c, REPO)
        parts.append(c if re.fullmatch(r"[-\w./=(),]+", c) else "'" + c + "'")
    return " ".join(p for p in parts if p not in ("--stats", "-q"))


# --- stiff ----------------------------------------------------------------------------------------

def tolerance_runs(c, extra=(), events=False, tighter=()):
    """The runs of a smooth case, at SPICE's reltol 1e-3, at padsim's defaults (rtol 1e-8) and at
    each rtol of `tighter`, each with the arguments `extra`: (label, rtol, tolerance arguments,
    run) for each run that succeeds; a run that fails is recorded as a failed criterion."""
    runs = [("rtol 1e-3", 1e-3, ["--rtol", "1e-3"]), ("default", DEFAULT_RTOL, [])]
    runs += [(f"rtol {rtol:g}", rtol, ["--rtol", f"{rtol:g}"]) for rtol in tighter]
    for label, rtol, args in runs:
        r = c.run(args=list(extra) + args, tag=label.replace(" ", "_"), events=events)
        if not c.expect(r.returncode == 0, f"{label}: the run succeeds ({describe_status(r.returncode)})"):
            c.figure(f"{label}: {r.error_text()}")
            continue
        yield label, rtol, args, r


def check_lag_columns(c, columns, tighter=()):
    """columns: {probe: (exact function, size)}; each run's error must be within 10 rtol x size."""
    for label, rtol, args, r in tolerance_runs(c, tighter=tighter):
        worst = None
        for probe, (exact, size) in columns.items():
            err, at = max_error(r, probe, exact)
            text = f"{label}: {probe} max error {g(err)} (at t = {g(at)} s) <= 10 rtol x {g(size)} = {g(10 * rtol * size)}"
            c.expect(err <= 10 * rtol * size, text)
            if worst is None or err / size > worst[0]:
                worst = (err / size, text)
        if worst:
            c.key.append(worst[1])
        c.stats_figure(r, f"{label}: ")


def case_stiff_time_constants(c):
    taus = [1e-12, 1e-9, 1e-6, 1e-3, 1.0]
    check_lag_columns(c, {f"v(n{k + 1})": ((lambda t, k=k: lag_response(taus[:k + 1], t, 1e-6, 1e-12)), 1.0)
                          for k in range(5)})


def case_uic_start_fast_rc(c):
    r = c.run(tag="default")
    if not c.expect(r.returncode == 0, f"the run succeeds ({describe_status(r.returncode)})"):
        return
    first = r.rows[0]
    n1, n2 = r.header.index("v(n1)"), r.header.index("v(n2)")
    c.expect(first[0] == 0 and abs(first[n1]) <= 1e-6,
             f"first row (t = {g(first[0])}): v(n1) = {g(first[n1])}, the IC 0 within VNTOL 1e-6", key=True)
    c.expect(abs(first[n2]) <= 1e-6, f"first row: v(n2) = {g(first[n2])} within 1e-6")
    for probe, tau in (("v(n1)", 1e-12), ("v(n2)", 1.0)):
        err, at = max_error(r, probe, lambda t, tau=tau: -math.expm1(-t / tau))
        c.expect(err <= 10 * DEFAULT_RTOL, f"{probe} max error {g(err)} (at t = {g(at)} s) <= 10 rtol = {g(10 * DEFAULT_RTOL)}",
                 key=probe == "v(n1)")
    c.figure(f"first row: v(n1) = {g(first[n1])} V, v(n2) = {g(first[n2])} V")
    c.stats_figure(r)


def switch_waveform(t, transitions, c_farad=1e-6, r=1e3, ron=1e-3, roff=1e12, vin=1.0):
    """v(out) of switch_ron_roff_1e15: RC pieces between the switch's transitions."""
    v, t_prev, on = 0.0, 0.0, False
    for t_switch in transitions + [math.inf]:
        t_end = min(t, t_switch)
        rs = ron if on else roff
        v_inf = vin * rs / (r + rs)
        tau = c_farad * r * rs / (r + rs)
        v = v_inf + (v - v_inf) * math.exp(-(t_end - t_prev) / tau)
        if t <= t_switch:
            return v
        t_prev, on = t_switch, not on
    return v


def case_switch_ron_roff_1e15(c):
    transitions = [1e-3 + 0.5e-9, 2e-3 + 1.5e-9, 3e-3 + 0.5e-9, 4e-3 + 1.5e-9]
    for label, rtol, args, r in tolerance_runs(c, events=True):
        times = [e["time"] for e in r.events]
        c.expect(len(times) == 4, f"{label}: 4 switching events ({len(times)})")
        if len(times) == 4:
            dt = max(abs(a - b) for a, b in zip(times, transitions))
            c.expect(dt <= 1e-12, f"{label}: switching instants within {g(dt)} s of the control edges' 0.5 V crossings (<= 1e-12 s)",
                     key=not args)
        err, at = max_error(r, "v(out)", lambda t: switch_waveform(t, transitions))
        c.expect(err <= 10 * rtol, f"{label}: v(out) max error {g(err)} V (at t = {g(at)} s) <= 10 rtol x 1 V", key=True)
        on_level = 1e-3 / (1e3 + 1e-3)
        plateau = [(t, v) for t, v in zip(r.times(), r.column("v(out)"))
                   if transitions[0] + 100e-9 <= t <= transitions[1] or transitions[2] + 100e-9 <= t <= transitions[3]]
        rel = max(abs(v / on_level - 1) for _, v in plateau) if plateau else math.inf
        c.expect(rel <= 1e-3, f"{label}: closed-switch level {g(on_level)} V (RON's divider) to {g(rel)} relative (<= 1e-3)")
        c.stats_figure(r, f"{label}: ")


def inductor_into_roff_current(t, t_open=1e-3 + 0.5e-9, vin=5.0, r=1.0, ron=1.0, roff=1e12, inductance=1e-3):
    """i(l1) of switch_opens_inductor_into_roff: the closed switch's steady current, then its decay
    into ROFF, and the slope there."""
    i_on, i_off, tau = vin / (r + ron), vin / (r + roff), inductance / (r + roff)
    if t < t_open:
        return i_on, 0.0
    decay = (i_on - i_off) * math.exp(-(t - t_open) / tau)
    return i_off + decay, -decay / tau


def case_switch_opens_inductor_into_roff(c):
    t_open, i_on, v_settled = 1e-3 + 0.5e-9, 2.5, 5.0 * 1e12 / (1 + 1e12)
    for label, rtol, args, r in tolerance_runs(c, events=True, tighter=(1e-6, 1e-10)):
        times = [e["time"] for e in r.events]
        deviation = abs(times[0] / t_open - 1) if len(times) == 1 else math.inf
        c.expect(deviation <= 1e-12, f"{label}: one event ({len(times)}), {g(deviation)} relative from {t_open!r} s (<= 1e-12)")
        expect_rows_to_tstop(c, r, 2e-3, label=f"{label}: ")
        # A row's time is its instant only to its rounding: the decay moves 2.5e15 A/s, 5e-4 A
        # per ulp of t at 1 ms. Each row's error is taken beyond 32 ulps of that; the row before
        # the event (its time the same as the next row's) is the state before it.
        t_col, i_col = r.times(), r.column("i(l1)")
        worst, at = 0.0, None
        for k, (t, i) in enumerate(zip(t_col, i_col)):
            if k + 1 < len(t_col) and t_col[k + 1] == t:
                continue
            exact, slope = inductor_into_roff_current(t)
            err = max(0.0, abs(i - exact) - abs(slope) * 32 * sys.float_info.epsilon * t)
            if err > worst:
                worst, at = err, t
        c.expect(worst <= 10 * rtol * i_on,
                 f"{label}: i(l1) within {g(worst)} A of the closed form (at t = {g(at)} s) <= 10 rtol x {g(i_on)} A",
                 key=not args)
        v_end = r.column("v(c)")[-1]
        c.expect(abs(v_end - v_settled) <= 10 * rtol * 5.0,
                 f"{label}: v(c) at tstop {v_end!r} V, ROFF's divider {v_settled!r} V within 10 rtol x 5 V")
        c.stats_figure(r, f"{label}: ")


def case_inductors_1p_1meg(c):
    i2_size = lag_response([1e6], 1.0, 1e-6, 1e-12)
    check_lag_columns(c, {"i(l1)": (lambda t: lag_response([1e-12], t, 1e-6, 1e-12), 1.0),
                          "i(l2)": (lambda t: lag_response([1e6], t, 1e-6, 1e-12), i2_size)})


def case_capacitors_1e_18_1(c):
    # At rtol 1e-8 and 1e-9 the ramp's start asks for steps at the time resolution (4e-21 s at
    # 1 us): the step reduced below the minimum tries the minimum itself, and the error test
    # grants what the rounding of t leaves unresolved (|v'| ulp(t)).
    check_lag_columns(c, {"v(a)": (lambda t: lag_response([1e-18], t, 1e-6, 1e-12), 1.0),
                          "v(b)": (lambda t: lag_response([1.0], t, 1e-6, 1e-12), 1.0)}, tighter=(1e-8, 1e-9))


def case_volts_1e6_and_1e_9(c):
    hv = lambda t: 1e6 * lag_response([1e-3], t, 0, 1e-6)
    lv = lambda t: 1e-9 * lag_response([1e-3, 1e-4], t, 0, 1e-6)
    # At SPICE's tolerances (reltol 1e-3, VNTOL 1 uV) a 1 nV node is below the absolute
    # tolerance: only VNTOL bounds its error. Asking for it (--atol 1e-15: every unknown's
    # absolute tolerance) must give it the relative accuracy of the rest, without upsetting the
    # 1 MV node.
    for label, rtol, args, lv_bound in (("rtol 1e-3", 1e-3, ["--rtol", "1e-3"], 1e-6),
                                        ("rtol 1e-3, atol 1e-15", 1e-3, ["--rtol", "1e-3", "--atol", "1e-15"],
                                         10 * 1e-3 * 1e-9)):
        r = c.run(args=args, tag=label.replace(" ", "_"))
        if not c.expect(r.returncode == 0, f"{label}: the run succeeds ({describe_status(r.returncode)})"):
            c.figure(f"{label}: {r.error_text()}")
            continue
        err, at = max_error(r, "v(hv)", hv)
        c.expect(err <= 10 * rtol * 1e6, f"{label}: v(hv) max error {g(err)} V (at {g(at)} s) <= 10 rtol x 1e6 V")
        err, at = max_error(r, "v(lv)", lv)
        c.expect(err <= lv_bound, f"{label}: v(lv) max error {g(err)} V = {g(err / 1e-9)} of 1 nV (at {g(at)} s) <= {g(lv_bound)} V")
        c.stats_figure(r, f"{label}: ")


def lc_measure(r):
    """Amplitude sqrt(v^2 + (L/C) i^2) over the rows (L = 1 H, C = 1/(4 pi^2) F), and the phase
    at the last row (exactly 0 mod 2 pi at t = 10000 s), in periods."""
    ratio = 2 * math.pi  # sqrt(L / C)
    v, i = r.column("v(t)"), r.column("i(l1)")
    amplitude = [math.hypot(a, ratio * b) for a, b in zip(v, i)]
    theta = math.atan2(ratio * i[-1], v[-1])
    return amplitude, theta / (2 * math.pi)


def case_lc_tank_10000_periods(c):
    # The netlist asks for the trapezoidal rule (.options method=trap), which has no damping; BDF
    # (--method gear, padsim's default) is measured beside it.
    r = c.run(tag="trap")
    if not c.expect(r.returncode == 0, f"the run succeeds ({describe_status(r.returncode)})"):
        c.figure(r.error_text())
        return
    amplitude, phase = lc_measure(r)
    drift = max(abs(a - 1) for a in amplitude)
    c.expect(drift <= 1e-3, f"method=trap, default tolerances: amplitude in the last period {g(min(amplitude))} .. "
                            f"{g(max(amplitude))}: drift {g(drift)} <= 1e-3", key=True)
    c.figure(f"trap: phase error after 10,000 periods {g(phase)} periods")
    c.stats_figure(r, "trap: ")
    for rtol in ((None, "1e-6", "1e-9") if c.full else (None,)):
        args = ["--method", "gear"] + (["--rtol", rtol] if rtol else [])
        label = "gear" + (f" rtol {rtol}" if rtol else ", default tolerances")
        r = c.run(args=args, tag="gear" + (rtol or ""))
        if r.returncode != 0:
            c.figure(f"{label}: {describe_status(r.returncode)} {r.error_text()}")
            continue
        amplitude, phase = lc_measure(r)
        c.figure(f"{label} (informative): amplitude after 10,000 periods {g(amplitude[-1])}, drift "
                 f"{g(max(abs(a - 1) for a in amplitude))}, damping per period "
                 f"{g(-math.expm1(math.log(amplitude[-1]) / 10000))}, phase error {g(phase)} periods")
        c.stats_figure(r, f"{label}: ")


# --- events ---------------------------------------------------------------------------------------

def case_relay_chattering(c):
    r = c.run(tag="default")
    c.expect(r.returncode == 1, f"exit 1 ({describe_status(r.returncode)})")
    c.expect("event accumulation" in r.stderr or "chattering" in r.stderr,
             "the diagnostic says event accumulation / chattering")
    c.expect("b1" in r.error_text(), "the diagnostic names the relay b1", key=True)
    tf = r.failure_time()
    c.expect(tf is not None and abs(tf - 1) <= 1e-6, f"stopped at t = {g(tf)} s (x reaches 0 at 1 s; within 1e-6 s)", key=True)
    c.figure("diagnostic: " + r.error_text())
    if r.rows:
        err, at = max_error(r, "v(x)", lambda t: 1 - t)
        c.expect(err <= 1e-6, f"rows kept: v(x) = 1 - t to {g(err)} (<= 1e-6)")
        c.expect(r.rows[-1][0] >= 0.9, f"rows kept up to t = {g(r.rows[-1][0])} s (>= 0.9 s)")
    else:
        c.expect(False, "rows kept before the failure")
    c.stats_figure(r)


def relay_level():
    """u when one switch is closed: 1 V through RON = 1 mohm, -1 V through ROFF = 1 Gohm, 1 Mohm load."""
    gon, goff, gl = 1e3, 1e-9, 1e-6
    return (gon - goff) / (gon + goff + gl)


def case_relay_hysteresis(c):
    r = c.run(tag="default", events=True)
    if not c.expect(r.returncode == 0, f"the run succeeds ({describe_status(r.returncode)})"):
        c.figure(r.error_text())
        return
    u = relay_level()
    exact, t = [], (1 + 1e-3) / u
    while t < 3:
        exact.append(t)
        t += 2e-3 / u
    times = sorted(set(e["time"] for e in r.events))
    c.expect(len(times) == len(exact), f"{len(times)} switching instants ({len(exact)} in the closed form)")
    flips = {}
    for e in r.events:
        flips[e["time"]] = flips.get(e["time"], 0) + 1
    c.expect(all(n == 2 for n in flips.values()), "both switches flip at every instant")
    if times and len(times) == len(exact):
        dt = max(abs(a - b) for a, b in zip(times, exact))
        c.expect(dt <= 1e-9, f"every instant within {g(dt)} s of the closed form (<= 1e-9 s; half period 2 ms)", key=True)
    err, at = max_error(r, "v(x)", lambda t: x_relay(t, exact, u))
    c.expect(err <= 1e-6, f"v(x) max error {g(err)} V (at t = {g(at)} s) <= 1e-6 V")
    c.stats_figure(r)


def x_relay(t, instants, u):
    if not instants or t <= instants[0]:
        return 1 - u * t
    k = 0
    while k + 1 < len(instants) and instants[k + 1] <= t:
        k += 1
    going_up = k % 2 == 0
    return -1e-3 + u * (t - instants[k]) if going_up else 1e-3 - u * (t - instants[k])


def freewheel_closed_form():
    """diode_freewheel_to_zero: (segments, t_open, t_zero); segment k = (t_start, t_end, x0, A, b)
    for x = (i(l1), v(out))."""
    l, cap, res, vin = 100e-6, 10e-6, 100.0, 10.0
    a = [[0.0, -1 / l], [1 / cap, -1 / (res * cap)]]
    t_open = 10.0005e-6
    x1 = affine2(a, [vin / l, 0.0], [0.0, 5.0], t_open)
    t_zero = t_open + bisect(lambda s: affine2(a, [0.0, 0.0], x1, s)[0], 0.0, 50e-6)
    x2 = affine2(a, [0.0, 0.0], x1, t_zero - t_open)
    return (lambda t: affine2(a, [vin / l, 0.0], [0.0, 5.0], t) if t <= t_open else
            affine2(a, [0.0, 0.0], x1, t - t_open) if t <= t_zero else
            [0.0, x2[1] * math.exp(-(t - t_zero) / (res * cap))]), t_open, t_zero


def case_diode_freewheel_to_zero(c):
    exact, t_open, t_zero = freewheel_closed_form()
    for label, rtol, args, r in tolerance_runs(c, extra=["--probe", "i(l1),v(out),v(a)"], events=True):
        flips = [(e["element"], e["from"], e["to"]) for e in r.events]
        c.expect(flips == [("s1", "1", "0"), ("d1", "0", "1"), ("d1", "1", "0")],
                 f"{label}: three flips: s1 off and d1 on together, then d1 off ({len(flips)} flips)")
        if len(r.events) == 3:
            c.expect(r.events[0]["time"] == r.events[1]["time"] and abs(r.events[0]["time"] - t_open) <= 1e-12,
                     f"{label}: s1 opens at {g(r.events[0]['time'])} s (10.0005 us)")
            dt = abs(r.events[2]["time"] - t_zero)
            c.expect(dt <= 10 * rtol * 10e-6, f"{label}: d1 turns off at {r.events[2]['time']:.9g} s, "
                                              f"{g(dt)} s from the closed form {t_zero:.9g} s (<= 10 rtol x 10 us)",
                     key=not args)
        i_max = max(abs(exact(t)[0]) for t in [k * 1e-7 for k in range(1000)])
        err_i, at_i = max_error(r, "i(l1)", lambda t: exact(t)[0])
        err_v, at_v = max_error(r, "v(out)", lambda t: exact(t)[1])
        c.expect(err_i <= 10 * rtol * i_max, f"{label}: i(l1) max error {g(err_i)} A (at {g(at_i)} s) <= 10 rtol x {g(i_max)} A")
        c.expect(err_v <= 10 * rtol * 5, f"{label}: v(out) max error {g(err_v)} V (at {g(at_v)} s) <= 10 rtol x 5 V")
        after = [abs(i) for t, i in zip(r.times(), r.column("i(l1)")) if t > t_zero + 1e-9]
        c.expect(after and max(after) <= 1e-9, f"{label}: i(l1) = 0 after the turn-off (max {g(max(after) if after else None)} A)")
        c.stats_figure(r, f"{label}: ")


def case_diode_turnoff_at_peak(c):
    r = c.run(args=["--probe", "i(vsense),v(out)"], tag="default", events=True)
    if not c.expect(r.returncode == 0, f"the run succeeds ({describe_status(r.returncode)})"):
        c.figure(r.error_text())
        return
    flips = [(e["time"], e["to"]) for e in r.events if e["element"] == "d1"]
    c.expect(len(flips) == 6, f"6 diode flips in 3 cycles (on, off per cycle): {len(flips)}", key=True)
    same_instant = sum(1 for a, b in zip(flips, flips[1:]) if a[0] == b[0])
    c.figure(f"diode flips {len(flips)}, of which {same_instant} undo the previous one at the same instant")
    off_intervals, start = [], None
    for t, to in flips:
        if to == "0":
            start = t
        elif start is not None:
            off_intervals.append((start, t))
            start = None
    if start is not None:
        off_intervals.append((start, math.inf))
    # While off (from the first turn-off to the next turn-on the closed form allows: the source
    # reaching v(out) + 0.7 V again, after 15 ms at the earliest).
    first_off = next((t for t, to in flips if to == "0"), None)
    if first_off is not None:
        window = [abs(i) for t, i in zip(r.times(), r.column("i(vsense)")) if first_off < t < first_off + 15e-3]
        worst = max(window) if window else 0.0
        c.expect(worst <= 1e-6, f"i(vsense) after the first turn-off, for 15 ms: max {g(worst)} A (<= 1 uA; ROFF leaks 10 nA)")
    c.stats_figure(r)


def twisting_instants(n):
    """Switching instants of x'' = -3 sign(x) - sign(x') from x = 1: x = 0 after sqrt(X), x' = 0
    after 0.5 sqrt(X) more, then X halves."""
    out, t, amplitude = [], 0.0, 1.0
    while len(out) < n:
        t += math.sqrt(amplitude)
        out.append(t)
        t += 0.5 * math.sqrt(amplitude)
        out.append(t)
        amplitude /= 2
    return out[:n]


def case_zeno_twisting(c):
    t_star = 1.5 / (1 - 1 / math.sqrt(2))
    for label, args in (("default", []), ("rtol 1e-9, atol 1e-12", ["--rtol", "1e-9", "--atol", "1e-12"])):
        tag = "default" if not args else "tight"
        r = c.run(args=["--probe", "v(x),v(v)"] + args, tag=tag, events=True)
        c.expect(r.returncode == 1, f"{label}: exit 1 ({describe_status(r.returncode)})")
        c.expect("event accumulation" in r.stderr, f"{label}: an event accumulation diagnostic")
        tf = r.failure_time()
        c.figure(f"{label}: stopped at t = {g(tf)} s ({len(r.events)} flips): {r.error_text()}")
        if args:
            c.expect(tf is not None and abs(tf - t_star) <= 1e-3,
                     f"{label}: stopped at t = {tf} s, within 1e-3 s of t* = {t_star:.9g} s", key=True)
            exact = twisting_instants(20)
            times = [e["time"] for e in r.events[:20]]
            if c.expect(len(times) == 20, f"{label}: at least 20 switchings ({len(r.events)})"):
                dt = max(abs(a - b) for a, b in zip(times, exact))
                c.expect(dt <= 1e-6, f"{label}: the first 20 switching instants within {g(dt)} s of the closed form (<= 1e-6 s)")
        else:
            c.expect(tf is not None and tf < 8, f"{label}: stopped before TSTOP (t = {g(tf)} s; t* = {t_star:.6g} s)", key=True)
        c.stats_figure(r, f"{label}: ")


def sharing_sequence(t_end, tau=math.inf, current=1e-3, cap=1e-6):
    """Charge-sharing relaxation (zeno_charge_sharing, flip_back_after_jump): the events
    (time, v2 before, shared voltage, jump energy) up to t_end."""
    out, t, v1, v2 = [], 0.0, 0.0, 0.0
    while True:
        dt = (1 - v1) * cap / current
        if dt <= 0 or t + dt > t_end or len(out) > 10000:
            return out
        t += dt
        v2 = v2 * math.exp(-dt / tau) if tau != math.inf else v2
        shared = (1 + v2) / 2
        out.append((t, v2, shared, cap * (1 - v2) ** 2 / 4))
        v1 = v2 = shared


def sharing_events(r):
    """S1's closings, each with the flips that follow it within 1e-12 s (the opening, in the same
    event or as the next one): [(time, [flips], jump energy)]."""
    out = []
    for e in r.events:
        flip = (e["element"], e["from"], e["to"])
        if out and e["time"] - out[-1][0] <= 1e-12 and flip != ("s1", "0", "1"):
            out[-1][1].append(flip)
        else:
            out.append((e["time"], [flip], e["jump_energy"]))
    return out


def check_sharing_events(c, r, exact, n, dt_bound, dv_bound, label=""):
    """The first n events against the closed form: S1 closes and opens again at once, the closing
    times, the shared voltages after the jump, and the jump energy against the jump's own
    voltages (C/4 (v1 - v2)^2 from the row before it)."""
    got = sharing_events(r)
    n = min(n, len(exact))
    if not c.expect(len(got) >= n, f"{label}at least {n} events ({len(got)})"):
        return
    got, exact = got[:n], exact[:n]
    c.expect(all(f == [("s1", "0", "1"), ("s1", "1", "0")] for _, f, _ in got),
             f"{label}at each of them S1 closes and opens again at once")
    dt = max(abs(a[0] - b[0]) for a, b in zip(got, exact))
    c.expect(dt <= dt_bound, f"{label}closing times within {g(dt)} s of the closed form (<= {g(dt_bound)} s)", key=True)
    k_c1, k_c2 = r.header.index("v(c1)"), r.header.index("v(c2)")
    worst_v, worst_e = 0.0, 0.0
    for (t_event, _, energy), (_, _, shared, _) in zip(got, exact):
        at = [row for row in r.rows if row[0] == t_event]
        before = [row for row in r.rows if row[0] < t_event]
        if len(at) < 2 or not before:
            worst_v = worst_e = math.inf
            continue
        worst_v = max(worst_v, abs(at[-1][k_c1] - shared), abs(at[-1][k_c2] - shared))
        own = 1e-6 * (at[0][k_c1] - at[0][k_c2]) ** 2 / 4
        worst_e = max(worst_e, abs(energy / own - 1))
    c.expect(worst_v <= dv_bound, f"{label}v(c1) = v(c2) = (1 + v2) / 2 after every jump, to {g(worst_v)} V (<= {g(dv_bound)} V)")
    c.expect(worst_e <= 1e-6, f"{label}jump energy = C/4 (v1 - v2)^2 of the jump's own voltages, to {g(worst_e)} relative")


def case_zeno_charge_sharing(c):
    t_star = 2e-3
    r = c.run(tag="default", events=True)
    exact = sharing_sequence(t_star)
    # Before the accumulation the events are exact (C1 charges linearly): the first five.
    check_sharing_events(c, r, exact, 5, 1e-9, 1e-6)
    got = sharing_events(r)
    c.figure(f"{len(got)} events resolved, the last at {g(got[-1][0]) if got else '-'} s")
    stair = lambda t: next((e[2] for e in reversed(exact) if e[0] <= t), 0.0)
    if r.returncode == 1:
        # Stopped with a diagnostic at the accumulation point.
        c.expect("event accumulation" in r.stderr, "stopped with an event accumulation diagnostic")
        tf = r.failure_time()
        c.expect(tf is not None and abs(tf - t_star) <= 1e-6, f"stopped at t = {g(tf)} s, within 1 us of t* = 2 ms", key=True)
        c.figure("diagnostic: " + r.error_text())
    else:
        # Or carried on past it: S1 then stays closed and C1, C2 charge together at I / 2C.
        c.expect(r.returncode == 0, f"the run stops with a diagnostic (exit 1) or goes on to 3 ms (exit 0): {describe_status(r.returncode)}",
                 key=True)
        after = [(t, a, b) for t, a, b in zip(r.times(), r.column("v(c1)"), r.column("v(c2)")) if t >= t_star + 1e-6]
        err = max((max(abs(a - (1 + 500 * (t - t_star))), abs(b - (1 + 500 * (t - t_star)))) for t, a, b in after),
                  default=math.inf)
        c.expect(err <= 10 * DEFAULT_RTOL * 1.5, f"after t* both follow 1 + 500 (t - 2 ms) V (S1 closed), to {g(err)} V (<= 10 rtol x 1.5 V)")
        c.figure(f"padsim went on through the accumulation point: S1 stays closed from {g(got[-1][0]) if got else '-'} s "
                 f"(the closed form has infinitely many events between then and t*, C2 climbing the last "
                 f"{g(1 - stair(got[-1][0])) if got else '-'} V in steps)")
    c.stats_figure(r)


def case_flip_back_after_jump(c):
    exact = sharing_sequence(5e-3, tau=1e-3)
    # Each event's v(c2) error shifts every later event: the sequence amplifies the integration
    # error (measured: the times' error is about 200 rtol x 1 ms after 48 events, at any rtol).
    for label, args, n, dt_bound, dv_bound in (("rtol 1e-3", ["--rtol", "1e-3"], 10, 2e-5, 1e-2),
                                               ("rtol 1e-6, atol 1e-12", ["--rtol", "1e-6", "--atol", "1e-12"],
                                                len(exact), 1e-6, 1e-4)):
        tight = "--atol" in args
        r = c.run(args=args, tag="tight" if tight else "loose", events=True)
        if not c.expect(r.returncode == 0, f"{label}: the run succeeds ({describe_status(r.returncode)})"):
            c.figure(f"{label}: {r.error_text()}")
        if tight:
            c.expect(len(sharing_events(r)) == len(exact), f"{label}: {len(sharing_events(r))} events by 5 ms "
                                                           f"({len(exact)} in the closed form)")
        check_sharing_events(c, r, exact, n, dt_bound, dv_bound, f"{label}: ")
        c.stats_figure(r, f"{label}: ")


def case_simultaneous_100_switches(c):
    r = c.run(tag="default", events=True)
    if not c.expect(r.returncode == 0, f"the run succeeds ({describe_status(r.returncode)})"):
        c.figure(r.error_text())
        return
    times = set(e["time"] for e in r.events)
    c.expect(len(times) == 1 and len(r.events) == 100, f"one event ({len(times)}) with 100 flips ({len(r.events)})", key=True)
    elements = sorted(e["element"] for e in r.events)
    c.expect(elements == sorted(f"s{k}" for k in range(1, 101)) and all(e["to"] == "1" for e in r.events),
             "the flips are s1 ... s100 closing")
    if times:
        t = min(times)
        c.expect(abs(t - 1.0005e-6) <= 1e-15, f"at t = {t!r} s (the clock's 0.5 V crossing 1.0005 us, within 1e-15 s)")
    energy = sum((k * (101 - k) / 101) * 1e-9 * (k / 100) ** 2 / 2 for k in range(1, 101))
    if r.events:
        got = r.events[0]["jump_energy"]
        c.expect(abs(got / energy - 1) <= 1e-6, f"jump energy {got:.9g} J against {energy:.9g} J (1e-6 relative)", key=True)
    last = r.rows[-1]
    worst = 0.0
    for k in range(1, 101):
        shared = k * (k / 100) / 101
        for node in (f"v(a{k})", f"v(b{k})"):
            worst = max(worst, abs(last[r.header.index(node)] - shared))
    c.expect(worst <= 1e-9, f"every pair at k (k/100) / 101 V after the event, to {g(worst)} V (<= 1e-9 V)")
    c.stats_figure(r)


def case_source_capacitor_loop_tight(c):
    runs = {rtol: c.run(args=("--rtol", "%g" % rtol, "--grid"), tag="rtol%g" % rtol) for rtol in (1e-6, 1e-9)}
    for rtol, r in runs.items():
        c.expect(r.returncode == 0, f"rtol {g(rtol)}: exit 0 ({describe_status(r.returncode)}) {r.error_text()}",
                 key=True)
        expect_rows_to_tstop(c, r, 100e-6, label=f"rtol {g(rtol)}: ")
    r = runs[1e-6]
    if r.returncode == 0:
        reference = ngspice_reference(c, ["v(m)"], "reltol=1e-6 method=gear", 1e-9)
        if reference:
            # From 100 ns on: ngspice's first steps smear the charges' jump at t = 0.
            worst, at = difference_from(reference, r, "v(m)", t_from=100e-9)
            c.expect(worst <= 10 * 1e-6 * 380, f"rtol 1e-6: v(m) within {g(worst)} V of ngspice's (at {g(at)} s; "
                     f"<= 10 rtol x 380 V)", key=True)
    c.stats_figure(r)


def case_first_step_events(c):
    r = c.run(args=["--probe", "v(a),v(c2),v(s1out),v(ctl2)"], tag="default", events=True)
    if not c.expect(r.returncode == 0, f"the run succeeds ({describe_status(r.returncode)})"):
        c.figure(r.error_text())
        return
    t_s1 = -math.log1p(-1e-9)
    by = {e["element"]: e for e in r.events}
    c.expect(sorted(by) == ["s1", "s2"] and len(r.events) == 2, f"two events, s1 and s2 closing ({len(r.events)} flips)")
    if "s2" in by:
        c.expect(abs(by["s2"]["time"] - 0.5e-12) <= 1e-18, f"s2 closes at {by['s2']['time']!r} s (0.5 ps, within 1e-18 s)", key=True)
    if "s1" in by:
        dt = abs(by["s1"]["time"] - t_s1)
        c.expect(dt <= 1e-14, f"s1 closes at {by['s1']['time']!r} s, {g(dt)} s from -ln(1 - 1e-9) s (within 1e-14 s)", key=True)
    t2 = by["s2"]["time"] if "s2" in by else 0.5e-12
    tau2 = 1e-9 * 1 * 1e12 / (1 + 1e12)
    err, at = max_error(r, "v(c2)", lambda t: 1.0 if t < t2 else math.exp(-(t - t2) / tau2), keep=lambda t: t > t2)
    c.expect(err <= 10 * DEFAULT_RTOL, f"v(c2) max error {g(err)} V (at {g(at)} s) after s2 closes (<= 10 rtol)")
    err, at = max_error(r, "v(a)", lambda t: -math.expm1(-t))
    c.expect(err <= 10 * DEFAULT_RTOL, f"v(a) max error {g(err)} V (at {g(at)} s) (<= 10 rtol)")
    t1 = by["s1"]["time"] if "s1" in by else t_s1
    off, on = 1e9 / (1e9 + 1e3), 1 / (1 + 1e3)
    err, at = max_error(r, "v(s1out)", lambda t: off if t < t1 else on, keep=lambda t: t != t1)
    c.expect(err <= 1e-6, f"v(s1out) on the dividers ({g(off)} V, then {g(on)} V) to {g(err)} V")
    c.stats_figure(r)


def case_events_closer_than_min_step(c):
    r = c.run(tag="default", events=True)
    if not c.expect(r.returncode == 0 and r.rows and r.rows[-1][0] == 1.0,
                    f"the run reaches 1 s ({describe_status(r.returncode)})"):
        c.figure(r.error_text())
    flips = sorted((e["element"], e["to"]) for e in r.events)
    c.expect(flips == [("s1", "1"), ("s2", "1")], f"s1 and s2 close, once each ({len(r.events)} flips)")
    if r.events:
        dt = max(abs(e["time"] - 0.5) for e in r.events)
        c.expect(dt <= 1e-12, f"at 0.5 s (within {g(dt)} s); {len(set(e['time'] for e in r.events))} distinct event time(s)", key=True)
        energy = sum({e["time"]: e["jump_energy"] for e in r.events}.values())
        c.expect(abs(energy / 1.25e-6 - 1) <= 1e-6, f"total jump energy {energy:.9g} J (C/4 (1^2 + 2^2) = 1.25e-6 J)")
    if r.rows:
        last = r.rows[-1]
        worst = max(abs(last[r.header.index(n)] - v)
                    for n, v in (("v(a1)", 0.5), ("v(b1)", 0.5), ("v(a2)", 1.0), ("v(b2)", 1.0)))
        c.expect(worst <= 1e-9, f"shared voltages 0.5 V and 1 V to {g(worst)} V")
    c.stats_figure(r)


def case_source_jump_fast_rc(c):
    for label, rtol, args, r in tolerance_runs(c):
        err, at = max_error(r, "v(n1)", lambda t: lag_response([1e-9], t, 1e-6, 0), keep=lambda t: t != 1e-6)
        c.expect(err <= 10 * rtol, f"{label}: v(n1) max error {g(err)} V (at {g(at)} s) <= 10 rtol x 1 V")
        c.stats_figure(r, f"{label}: ")


def case_pwl_repeat_square_rc(c):
    tau, period, first_rise = 200e-9, 3e-6, 1.5e-6
    high, low = math.exp(-1e-6 / tau), math.exp(-2e-6 / tau)  # decay over the high and low parts

    def exact(t):
        # v_k, v(n1) at rise k, from v_{k+1} = low (1 - high) + low high v_k and v_0 = 0; then the
        # relaxation toward 1 V for 1 us and toward 0 for 2 us.
        if t <= first_rise:
            return 0.0
        k = math.ceil((t - first_rise) / period) - 1
        v_k = low * (1 - high) / (1 - low * high) * (1 - (low * high) ** k)
        u = t - (first_rise + k * period)
        if u <= 1e-6:
            return 1 + (v_k - 1) * math.exp(-u / tau)
        return (1 + (v_k - 1) * high) * math.exp(-(u - 1e-6) / tau)

    for label, rtol, args, r in tolerance_runs(c):
        err, at = max_error(r, "v(n1)", exact)
        c.expect(err <= 10 * rtol, f"{label}: v(n1) max error {g(err)} V (at {g(at)} s) <= 10 rtol x 1 V", key=True)
        c.stats_figure(r, f"{label}: ")


def charge_pump_switch_instants():
    """{switch: its closed-form instants over 10 us}: each gate PULSE (5 V in 5 ns) crosses 2.5 V
    2.5 ns into its rise and its fall; S1, S3, S5 on Vt1 (delay 600 ns), S2, S4 on Vt2 (100 ns)."""
    def crossings(delay):
        return [t for k in range(10) for t in (delay + k * 1e-6 + 2.5e-9, delay + k * 1e-6 + 307.5e-9)]
    return {s: crossings(600e-9 if s in ("s1", "s3", "s5") else 100e-9) for s in ("s1", "s2", "s3", "s4", "s5")}


def case_charge_pump_clock_edges(c):
    probes = ["v(n1)", "v(n4)", "v(out)"]
    runs = {rtol: c.run(args=["--probe", ",".join(probes), "--rtol", f"{rtol:g}"], tag=f"rtol{rtol:g}", events=True)
            for rtol in (1e-3, 1e-6, 1e-8)}
    exact = charge_pump_switch_instants()
    for rtol, r in runs.items():
        if not c.expect(r.returncode == 0, f"rtol {g(rtol)}: exit 0 ({describe_status(r.returncode)})", key=True):
            c.figure(f"rtol {g(rtol)}: {r.error_text()}")
            continue
        expect_rows_to_tstop(c, r, 10e-6, label=f"rtol {g(rtol)}: ")
        located = {s: sorted(e["time"] for e in r.events if e["element"] == s) for s in exact}
        counts_match = all(len(located[s]) == len(exact[s]) for s in exact)
        worst = max((abs(t - t_exact) / t_exact for s in exact for t, t_exact in zip(located[s], exact[s])), default=0.0)
        c.expect(counts_match and worst <= 1e-12, f"rtol {g(rtol)}: {len(r.events)} switch events (100), each within "
                 f"{g(worst)} relative of its gate's 2.5 V crossing (<= 1e-12)", key=rtol == 1e-6)
    r = runs[1e-6]
    reference = ngspice_reference(c, probes, "reltol=1e-6 method=gear", 0.2e-9) if r.returncode == 0 else None
    if not reference:
        return
    for probe in probes:
        span = spicecmp.signal_range(reference.signals[probe])
        # ngspice switches at its own time points: a step's lag at each switching instant.
        worst, at = difference_from(reference, r, probe, t_from=20e-9)
        c.expect(worst <= 1e-3 * span, f"rtol 1e-6: {probe} within {g(worst)} V of ngspice's (at {g(at)} s; <= 1e-3 x its "
                 f"range {g(span)} V)", key=probe == "v(out)")
    span = spicecmp.signal_range(reference.signals["v(out)"])
    for rtol, r in runs.items():
        if r.returncode != 0:
            continue
        error = abs(r.rows[-1][r.header.index("v(out)")] - reference.signals["v(out)"][-1])
        bound = 10 * max(rtol, 1e-6) * span
        c.expect(error <= bound, f"rtol {g(rtol)}: v(out) at 10 us within {g(error)} V of ngspice's (<= {g(bound)} V)")
    c.stats_figure(runs[1e-6])


# --- faults ---------------------------------------------------------------------------------------

def case_log_negative_off_path(c):
    exact = lambda t: math.log(max(math.sin(2 * math.pi * 1e3 * t), 1e-3))
    swing = -math.log(1e-3)
    for label, rtol, args, r in tolerance_runs(c, events=True):
        s = r.stats or {}
        c.expect(s.get("rejected_domain", 0) >= 1, f"{label}: steps cut outside the domain: {s.get('rejected_domain')}",
                 key=not args)
        c.expect(len(r.events) == 6, f"{label}: 6 threshold crossings in 3 periods ({len(r.events)})")
        at_events = lambda t: any(t == e["time"] for e in r.events)
        err, at = max_error(r, "v(out)", exact, keep=lambda t: not at_events(t))
        c.expect(err <= 10 * rtol * swing,
                 f"{label}: v(out) = ln(max(v(a), 1 mV)) to {g(err)} (at {g(at)} s; <= 10 rtol x {g(swing)}; rows at events aside)")
        err, at = max_error(r, "v(out)", exact, keep=at_events)
        c.figure(f"{label}: the rows written at the events (the state just before them, from the step's polynomial) "
                 f"are off by up to {g(err)} (at {g(at)} s)")
        c.stats_figure(r, f"{label}: ")


def fold_middle_branch(current):
    """The root of v^3 - 3 v + 1e-9 v = I on the middle branch (|v| < 1); past the fold (I > 2)
    there is none: the fold's v = -1."""
    if current >= 2 * (1 - 1e-9 / 3) ** 1.5:
        return -1.0
    return bisect(lambda v: v ** 3 - (3 - 1e-9) * v - current, -1.0, 0.0)


def case_newton_divergence(c):
    r = c.run(tag="default")
    c.expect(r.returncode == 1, f"exit 1 ({describe_status(r.returncode)})")
    tf = r.failure_time()
    t_fold = 2e-3 / 3
    c.expect(tf is not None and abs(tf - t_fold) <= 1e-7, f"stopped at t = {g(tf)} s (the fold at 2/3 ms, within 0.1 us)", key=True)
    c.expect("node a" in r.stderr, "the diagnostic names node a", key=True)
    c.figure("diagnostic: " + r.error_text())
    c.expect(len(r.rows) >= 10 and r.rows[-1][0] >= 0.99 * t_fold,
             f"rows kept: {len(r.rows)}, the last at {g(r.rows[-1][0] if r.rows else None)} s")
    if r.rows:
        err, at = max_error(r, "v(a)", lambda t: fold_middle_branch(3e3 * t))
        c.expect(err <= 10 * DEFAULT_RTOL, f"the rows kept follow the branch to {g(err)} V (at {g(at)} s; <= 10 rtol x 1 V)")
    c.stats_figure(r)


def case_three_phase_rectifier_output_capacitor(c):
    vm, w, ls = 100, 2 * math.pi * 50, 2e-3
    for label, args in (("default", []), ("rtol 1e-5", ["--rtol", "1e-5"])):
        r = c.run(args=["--probe", "v(p,n),i(ld)"] + args, tag=label.replace(" ", "_"))
        if not c.expect(r.returncode == 0, f"{label}: the run reaches TSTOP ({describe_status(r.returncode)})", key=True):
            c.figure(f"{label}: diagnostic: " + r.error_text())
            continue
        times, v, i = r.times(), r.column("v(p,n)"), r.column("i(ld)")

        def mean(values):
            pairs = [(t0, t1, y0, y1) for t0, t1, y0, y1 in zip(times, times[1:], values, values[1:]) if t0 >= 10e-3]
            return sum((t1 - t0) * (y0 + y1) / 2 for t0, t1, y0, y1 in pairs) / sum(t1 - t0 for t0, t1, _, _ in pairs)

        v_mean, i_mean = mean(v), mean(i)
        expected = 3 * math.sqrt(3) / math.pi * vm - 3 / math.pi * w * ls * i_mean
        c.expect(abs(v_mean - expected) <= 0.03 * expected,
                 f"{label}: mean v(p,n) over 10..20 ms {g(v_mean)} V against {g(expected)} V (Id = {g(i_mean)} A; within 3 %)",
                 key=True)
        c.stats_figure(r, f"{label}: ")


def case_sqrt_argument_jumps_negative(c):
    r = c.run(tag="default")
    c.expect(r.returncode == 1, f"exit 1 ({describe_status(r.returncode)})")
    tf = r.failure_time()
    c.expect(tf is not None and abs(tf - 0.5e-3) <= 1e-9, f"stopped at t = {g(tf)} s (the step at 0.5 ms, within 1 ns)", key=True)
    c.expect("element b1" in r.stderr, "the diagnostic names b1", key=True)
    c.figure("diagnostic: " + r.error_text())
    c.expect(len(r.rows) >= 10 and r.rows[-1][0] >= 0.45e-3,
             f"rows kept: {len(r.rows)}, the last at {g(r.rows[-1][0] if r.rows else None)} s")
    if r.rows:
        err, at = max_error(r, "v(out)", lambda t: 1.0)
        c.expect(err <= 1e-9, f"the rows kept are v(out) = 1 V to {g(err)} V (at {g(at)} s)")
    c.stats_figure(r)


def expect_stops_at_gate_edge(c, r, names, probe, value):
    """A run whose switches reach, at the gate edge (1 us + 0.5 ns), a mode in which no state
    exists: exit 1 there, the fault named, the rows before kept and at their closed form."""
    c.expect(r.returncode == 1, f"exit 1 ({describe_status(r.returncode)})")
    tf = r.failure_time()
    c.expect(tf is not None and abs(tf - 1.0005e-6) <= 1e-12, f"stopped at t = {g(tf)} s (the gate edge, within 1 ps)", key=True)
    c.expect(all(name in r.stderr for name in names), "the diagnostic names " + ", ".join(names), key=True)
    c.figure("diagnostic: " + r.error_text())
    c.expect(len(r.rows) >= 10 and r.rows[-1][0] >= 0.99e-6,
             f"rows kept: {len(r.rows)}, the last at {g(r.rows[-1][0] if r.rows else None)} s")
    if r.rows:
        err, at = max_error(r, probe, lambda t: value)
        c.expect(err <= 1e-9, f"the rows kept are {probe} = {g(value)} V to {g(err)} V (at {g(at)} s)")
    c.stats_figure(r)


def case_current_source_switch_opens(c):
    expect_stops_at_gate_edge(c, c.run(tag="default"), ["cut-set of current sources", "node(s) a", "i1"], "v(b)", 1.0)


def case_switches_close_source_loop(c):
    expect_stops_at_gate_edge(c, c.run(tag="default"), ["loop of voltage sources", "v1", "v2", "s1", "s2"], "v(c)", 0.0)


def relaxation_cap(t, rc=1e-3):
    """v(cap) of circuits/relaxation_oscillator.cir from 3 V: down towards -5 V until -2.5 V
    (t1 = RC ln 3.2), then between +-2.5 V towards +-5 V, each half period RC ln 3."""
    t1, half = rc * math.log(3.2), rc * math.log(3.0)
    if t <= t1:
        return -5 + 8 * math.exp(-t / rc)
    k = math.floor((t - t1) / half)
    rising = k % 2 == 0
    target, start = (5.0, -2.5) if rising else (-5.0, 2.5)
    return target + (start - target) * math.exp(-(t - t1 - k * half) / rc)


def expect_rows_to_tstop(c, r, tstop, label="", key=False):
    """The run's rows reach tstop (within round-off of it)."""
    c.expect(bool(r.rows) and r.rows[-1][0] >= tstop * (1 - 1e-12),
             f"{label}rows to tstop: {len(r.rows)}, the last at {g(r.rows[-1][0] if r.rows else None)} s", key=key)


def expect_relaxation_to_tstop(c, r):
    """The relaxation oscillator's run (tstop 10 ms) ended well and follows its closed form."""
    c.expect(r.returncode == 0, f"exit 0 ({describe_status(r.returncode)})", key=True)
    expect_rows_to_tstop(c, r, 0.01, key=True)
    if r.rows:
        # 2e-9 of the 5 V swing: a run at reltol 1e-6 is 1e-6 V off; tolerance_below_roundoff
        # 3.6e-10 V, tolerance_below_double_precision 1.4e-12 V (measured).
        err, at = max_error(r, "v(cap)", relaxation_cap)
        c.expect(err <= 1e-8, f"v(cap) follows the closed form to {g(err)} V (at {g(at)} s; <= 1e-8 V)", key=True)
    c.stats_figure(r)


def case_tolerance_below_roundoff(c):
    expect_relaxation_to_tstop(c, c.run(tag="default"))
    # Neighbours of the netlist's reltol 1e-12 / vntol 1e-15: before the error test's floor was
    # raised to the estimate's round-off, reltol 2e-12 and 5e-13 with vntol 1e-16 failed it where
    # v(cap) crosses zero (at 0.47 ms), and whether a run got through was a matter of its steps.
    for rtol, atol in ((2e-12, 1e-16), (5e-13, 1e-16), (1e-12, 1e-16)):
        expect_relaxation_to_tstop(c, c.run(args=("--rtol", "%g" % rtol, "--atol", "%g" % atol),
                                            tag="rtol%g_atol%g" % (rtol, atol)))


def case_tolerance_below_roundoff_junctions(c):
    r = c.run(args=("--grid",), tag="default")
    c.expect(r.returncode == 0, f"exit 0 ({describe_status(r.returncode)})", key=True)
    expect_rows_to_tstop(c, r, 0.06, key=True)
    if r.returncode == 0:
        # ngspice at vntol 1e-15 stops too (timestep too small at 6.6 ms): its reference is the
        # report's tight run of the bridge, at its default vntol.
        reference = ngspice_reference(c, ["v(p)", "v(n)"], "reltol=1e-6 method=gear", 6e-7)
        if reference:
            for probe in ("v(p)", "v(n)"):
                worst, at = difference_from(reference, r, probe)
                span = spicecmp.signal_range(reference.signals[probe])
                c.expect(worst <= 1e-5 * span, f"{probe} within {g(worst)} V of ngspice's (at {g(at)} s; <= 1e-5 x "
                         f"its range {g(span)} V)", key=True)
    c.stats_figure(r)


def boost_operating_point_out():
    """v(out) of tolerance_below_roundoff_operating_point at its operating point: D1 (IS 1e-9,
    N 1.5, RS 5 mohm, GMIN 1e-12 across the junction) from 5 V into Rload 20 ohm."""
    vt = 1.5 * 1.38064852e-23 * 300.15 / 1.6021766208e-19

    def diode(vj):
        return 1e-9 * math.expm1(vj / vt) + 1e-12 * vj

    vj = bisect(lambda v: diode(v) - (5 - v - 5e-3 * diode(v)) / 20, 0.0, 1.0)
    return 5 - vj - 5e-3 * diode(vj)


def case_tolerance_below_roundoff_operating_point(c):
    r = c.run(tag="default")
    c.expect(r.returncode == 0, f"exit 0 ({describe_status(r.returncode)})", key=True)
    expect_rows_to_tstop(c, r, 20e-6)
    if r.rows:
        exact = boost_operating_point_out()
        error = abs(r.rows[0][r.header.index("v(out)")] - exact)
        c.expect(error <= 1e-12, f"first row: v(out) {exact:.15g} V within {g(error)} V (<= 1e-12 V)", key=True)
    c.stats_figure(r)


def case_tolerance_below_double_precision(c):
    # A minute bounds the run: before padae::kSmallestRtol, the first 1.7e-5 s took 20 s.
    r = c.run(tag="default", timeout=60, quiet=False)
    c.expect("warning: reltol 1e-16 is below what double precision resolves; using 8.9e-16" in r.stderr,
             "warns that reltol 1e-16 is raised to 8.9e-16")
    expect_relaxation_to_tstop(c, r)


def kill_case(c, sig, extra=()):
    csv_path = c.workdir / "killed.csv"
    if csv_path.exists():
        csv_path.unlink()
    command = [c.padsim, str(c.netlist), "-o", str(csv_path), "--stats", "-q"] + list(extra)
    c.commands.append(display_command(command, c.workdir, None) + f"  # {sig.name} once the CSV has rows")
    # SIGALRM ends the run after 60 s whatever happens to this script: no run outlives the test.
    p = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, encoding="utf-8",
                         errors="replace", preexec_fn=lambda: signal.alarm(60))
    deadline = time.monotonic() + 50
    while time.monotonic() < deadline and p.poll() is None:
        if csv_path.exists() and csv_path.stat().st_size > 200:
            break
        time.sleep(0.02)
    time.sleep(0.3)  # mid-run, between flushes
    running = p.poll() is None
    p.send_signal(sig)
    try:
        out, stderr = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        out, stderr = p.communicate()
    c.expect(running, "padsim was still running when signalled")
    c.expect(p.returncode == -sig, f"padsim ended by {sig.name} ({describe_status(p.returncode)})", key=True)
    c.expect(not any(m in stderr for m in SANITIZER_MARKS), "no sanitizer report")
    text = csv_path.read_text() if csv_path.exists() else ""
    lines = text.split("\n")
    c.expect(lines and lines[0] == "time,v(x)", f"the CSV has its header ({lines[0] if lines else 'empty'!r})")
    # SIGKILL leaves no chance to finish a write, and Linux ends a write to a file early, at a
    # page boundary, when a fatal signal arrives: the last line may be cut. Every other row is
    # whole; SIGTERM's rows all are.
    if sig == signal.SIGKILL and not text.endswith("\n"):
        c.figure(f"the last line was cut by SIGKILL mid-write ({len(lines.pop())} characters)")
    else:
        c.expect(text.endswith("\n"), "the CSV ends with a whole row")
    rows, bad = [], 0
    for line in lines[1:]:
        if not line:
            continue
        fields = line.split(",")
        try:
            values = [float(x) for x in fields]
            if len(values) != 2 or not all(math.isfinite(v) for v in values):
                raise ValueError
            rows.append(values)
        except ValueError:
            bad += 1
    c.expect(bad == 0 and len(rows) >= 10, f"{len(rows)} whole rows, {bad} broken", key=True)
    c.expect(all(b[0] > a[0] for a, b in zip(rows, rows[1:])), "times increase")
    if rows:
        err = max(abs(v - math.exp(-t)) for t, v in rows)
        c.expect(err <= 10 * DEFAULT_RTOL, f"v(x) = exp(-t) to {g(err)} (<= 10 rtol)")
        c.figure(f"{len(rows)} rows, the last at t = {rows[-1][0]:.9g} s")
    if csv_path.exists():
        csv_path.unlink()  # tens of megabytes
    if sig == signal.SIGTERM:
        m = re.search(r"interrupted by SIGTERM at t = ([-+0-9.eE]+) s", stderr)
        c.expect(m is not None, "padsim says it was interrupted, and when")
        if m and rows:
            c.expect(abs(float(m.group(1)) - rows[-1][0]) <= 1e-6 * max(1.0, rows[-1][0]),
                     f"the last row is at the reported stop time {m.group(1)} s (all rows flushed)")
        c.figure("diagnostic: " + " ".join(line for line in stderr.splitlines() if "error:" in line))


def case_killed_sigterm(c):
    kill_case(c, signal.SIGTERM)


def case_killed_sigterm_grid(c):
    kill_case(c, signal.SIGTERM, ["--grid"])


def case_killed_sigkill(c):
    kill_case(c, signal.SIGKILL)


def case_power_at_zero(c):
    r = c.run(tag="default")
    if not c.expect(r.returncode == 0, f"the run succeeds ({describe_status(r.returncode)})"):
        c.figure(r.error_text())
        return
    err, at = max_error(r, "v(out)", lambda t: 1.0)
    c.expect(err <= 1e-9, f"v(out) = 1 V to {g(err)}", key=True)


# --- bad input ------------------------------------------------------------------------------------

def bad_input_header(path):
    """(what it checks, [expected stderr substrings]) from the file's leading comment lines:
    '* expect: TEXT' ({file} is the file's name), the rest is the description."""
    what, expected = [], []
    for line in path.read_text(errors="replace").splitlines():
        if not line.startswith("*"):
            break
        body = line[1:].strip()
        m = re.match(r"expect:\s?(.*)$", body)
        if m:
            expected.append(m.group(1).replace("{file}", path.name))
        else:
            what.append(body)
    return " ".join(what), expected


def check_bad_input(c, path):
    what, expected = bad_input_header(path)
    c.netlist = path
    r = c.run(netlist=path.name, tag="run", cwd=path.parent, timeout=120)
    c.expect(r.returncode == 2, f"exit 2 ({describe_status(r.returncode)})")
    c.expect(r.wall <= BAD_INPUT_SECONDS, f"refused in {r.wall:.2f} s (<= {BAD_INPUT_SECONDS} s)")
    c.expect(expected, "the file names its expected diagnostic")
    for text in expected:
        c.expect(text in r.stderr, f"stderr has: {text}")
    diagnostic = [line for line in r.stderr.splitlines() if "error" in line]
    c.figure(diagnostic[0] if diagnostic else r.stderr.strip().splitlines()[0] if r.stderr.strip() else "(nothing on stderr)")


# --- the registry ---------------------------------------------------------------------------------

NUMERIC_CASES = [
    ("stiff", "stiff_time_constants", case_stiff_time_constants),
    ("stiff", "uic_start_fast_rc", case_uic_start_fast_rc),
    ("stiff", "switch_ron_roff_1e15", case_switch_ron_roff_1e15),
    ("events", "switch_opens_inductor_into_roff", case_switch_opens_inductor_into_roff),
    ("stiff", "inductors_1p_1meg", case_inductors_1p_1meg),
    ("stiff", "capacitors_1e-18_1", case_capacitors_1e_18_1),
    ("stiff", "volts_1e6_and_1e-9", case_volts_1e6_and_1e_9),
    ("stiff", "lc_tank_10000_periods", case_lc_tank_10000_periods),
    ("events", "relay_chattering", case_relay_chattering),
    ("events", "relay_hysteresis", case_relay_hysteresis),
    ("events", "diode_freewheel_to_zero", case_diode_freewheel_to_zero),
    ("events", "diode_turnoff_at_peak", case_diode_turnoff_at_peak),
    ("events", "zeno_twisting", case_zeno_twisting),
    ("events", "zeno_charge_sharing", case_zeno_charge_sharing),
    ("events", "flip_back_after_jump", case_flip_back_after_jump),
    ("events", "simultaneous_100_switches", case_simultaneous_100_switches),
    ("events", "source_capacitor_loop_tight", case_source_capacitor_loop_tight),
    ("events", "first_step_events", case_first_step_events),
    ("events", "events_closer_than_min_step", case_events_closer_than_min_step),
    ("events", "source_jump_fast_rc", case_source_jump_fast_rc),
    ("events", "pwl_repeat_square_rc", case_pwl_repeat_square_rc),
    ("events", "charge_pump_clock_edges", case_charge_pump_clock_edges),
    ("faults", "log_negative_off_path", case_log_negative_off_path),
    ("faults", "newton_divergence", case_newton_divergence),
    ("faults", "sqrt_argument_jumps_negative", case_sqrt_argument_jumps_negative),
    ("faults", "three_phase_rectifier_output_capacitor", case_three_phase_rectifier_output_capacitor),
    ("faults", "current_source_switch_opens", case_current_source_switch_opens),
    ("faults", "switches_close_source_loop", case_switches_close_source_loop),
    ("faults", "tolerance_below_roundoff", case_tolerance_below_roundoff),
    ("faults", "tolerance_below_roundoff_junctions", case_tolerance_below_roundoff_junctions),
    ("faults", "tolerance_below_roundoff_operating_point", case_tolerance_below_roundoff_operating_point),
    ("faults", "tolerance_below_double_precision", case_tolerance_below_double_precision),
    ("faults", "killed_sigterm", case_killed_sigterm),
    ("faults", "killed_sigterm_grid", case_killed_sigterm_grid),
    ("faults", "killed_sigkill", case_killed_sigkill),
    ("faults", "power_at_zero", case_power_at_zero),
]


def bad_input_files():
    return sorted(BAD_DIR.glob("*.cir"))


def all_case_names():
    return [name for _, name, _ in NUMERIC_CASES] + ["bad_input." + p.stem for p in bad_input_files()]


def netlist_description(path):
    """The header comment of a case's netlist: (title, what it checks)."""
    lines = []
    for line in path.read_text().splitlines():
        if not line.startswith("*"):
            break
        lines.append(line[1:].strip())
    title = lines[0] if lines else path.stem
    checks = " ".join(lines[1:])
    checks = re.sub(r"^Checks:\s*", "", checks)
    return title, checks


def run_case(name, padsim, workdir, full=False):
    """Runs one case; returns its Context (criteria, figures, commands)."""
    if name.startswith("bad_input."):
        c = Context(name, padsim, workdir, full)
        check_bad_input(c, BAD_DIR / (name[len("bad_input."):] + ".cir"))
        return c
    for _, case_name, function in NUMERIC_CASES:
        if case_name == name:
            c = Context(name, padsim, workdir, full)
            try:
                function(c)
            except Exception as e:  # a broken run must show up as a failed criterion
                c.expect(False, f"the check itself raised {type(e).__name__}: {e}")
            return c
    raise SystemExit(f"no case '{name}' (robustness.py list)")


def passed(c):
    return bool(c.criteria) and all(ok for ok, _ in c.criteria)


# --- the report -----------------------------------------------------------------------------------

def git_description():
    """HEAD's short hash, and whether src/ has uncommitted changes (empty outside a checkout)."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "src"], cwd=REPO, capture_output=True, text=True).stdout
        changed = sorted(set(line[3:].split("/")[1] for line in dirty.splitlines() if line[3:].startswith("src/")))
        if not head:
            return ""
        return head + (f" (with uncommitted changes in src/{', src/'.join(changed)})" if changed else "")
    except OSError:
        return ""


def md(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def write_report(results, output, built_from, wall):
    numeric = [(grp, name) for grp, name, _ in NUMERIC_CASES]
    by_name = {c.name: c for c in results}
    bad = [c for c in results if c.name.startswith("bad_input.")]
    status = {}
    for c in results:
        ok = passed(c)
        status[c.name] = ("pass" if ok else "FAIL") if c.name not in KNOWN_FAILURES else \
                         ("known failure (now passes: remove it from KNOWN_FAILURES)" if ok else "known failure")
    n_pass = sum(1 for c in results if passed(c))
    out = io.StringIO()
    w = out.write
    w("# padsim robustness suite: measured results\n\n")
    w("Generated by `make robustness-report` (`tests/robustness/robustness.py report`); do not edit by hand.\n")
    w(f"padsim built from {built_from or 'an unknown source'}; {len(results)} cases, {n_pass} pass, "
      f"{sum(1 for c in results if not passed(c) and c.name in KNOWN_FAILURES)} known failures, "
      f"{sum(1 for c in results if not passed(c) and c.name not in KNOWN_FAILURES)} unexpected failures; "
      f"the whole report ran in {wall:.0f} s.\n\n")
    w("Each case is a netlist in `tests/robustness/cases/` (or `invalid/`) whose header says what it checks; "
      "CTest runs each as `robustness.<case>` (label `robustness`), in the normal and the ASan + UBSan build. "
      "Criteria are numbers against closed forms or invariants; \"10 rtol\" bounds a global error by ten times the "
      "relative tolerance of the run times the signal's size. Known failures are cases padsim fails today: "
      "CTest shows them as disabled, the reason is below, and they pass unchanged once padsim is fixed.\n\n")

    w("## Summary\n\n| group | case | result | measured |\n|---|---|---|---|\n")
    for grp, name in numeric:
        c = by_name.get(name)
        if not c:
            continue
        failing = [t for ok, t in c.criteria if not ok]
        headline = "; ".join(failing[:2] if failing else c.key or [c.criteria[-1][1] if c.criteria else ""])
        w(f"| {grp} | [{name}](#{name.replace('_', '_')}) | {status[name]} | {md(headline)} |\n")
    n_bad_ok = sum(1 for c in bad if passed(c))
    w(f"| bad input | [{len(bad)} malformed or singular netlists](#bad-input) | {n_bad_ok} of {len(bad)} pass | "
      f"exit 2 with the expected diagnostic, no crash |\n\n")

    if KNOWN_FAILURES:
        w("## Known failures\n\n")
        for name, reason in KNOWN_FAILURES.items():
            w(f"- **{name}**: {reason}\n")
        w("\n")

    for grp_title, grp in (("Stiff and extreme values", "stiff"), ("Events", "events"), ("Faults", "faults")):
        w(f"## {grp_title}\n\n")
        for g_, name in numeric:
            if g_ != grp or name not in by_name:
                continue
            c = by_name[name]
            title, checks = netlist_description(CASES_DIR / f"{name}.cir")
            w(f"### {name}\n\n{md(title)}. Netlist `tests/robustness/cases/{name}.cir`. Result: **{status[name]}**.\n\n")
            w(f"What it checks: {checks}\n\n")
            if name in KNOWN_FAILURES:
                w(f"Known failure: {KNOWN_FAILURES[name]}\n\n")
            w("Commands:\n\n")
            for cmd in c.commands:
                w(f"    {cmd}\n")
            w("\nCriteria (measured):\n\n")
            for ok, text in c.criteria:
                if text == "no sanitizer report" and ok:
                    continue
                w(f"- {'ok' if ok else '**FAIL**'}: {text}\n")
            if c.figures:
                w("\nFigures:\n\n")
                for f in c.figures:
                    w(f"- {f}\n")
            w("\n")

    w("## Bad input\n\n")
    w(f"{len(bad)} netlists in `tests/robustness/invalid/`, each run as `padsim FILE` from that directory; each must "
      "exit 2 with the diagnostic its header names (`* expect:` lines; file:line:column for the parser and "
      "elaboration, the elements and nodes for the circuit checks) and nothing from the sanitizers.\n\n")
    w("| file | what | exit | diagnostic (first error line) | result |\n|---|---|---|---|---|\n")
    for c in bad:
        stem = c.name[len("bad_input."):]
        what, _ = bad_input_header(BAD_DIR / f"{stem}.cir")
        exit_text = next((t for _, t in c.criteria if t.startswith("exit 2")), "")
        code = re.search(r"\((.*)\)", exit_text)
        w(f"| {stem}.cir | {md(what)} | {md(code.group(1) if code else '')} | `{md(c.figures[0] if c.figures else '')}` | "
          f"{'pass' if passed(c) else 'FAIL: ' + md('; '.join(t for ok, t in c.criteria if not ok))} |\n")
    w("\n")
    Path(output).write_text(out.getvalue())


# --- command line ---------------------------------------------------------------------------------

def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p_list = sub.add_parser("list")
    p_list.add_argument("--known-failures", action="store_true")
    p_run = sub.add_parser("run")
    p_run.add_argument("case")
    p_run.add_argument("--padsim", required=True)
    p_run.add_argument("--workdir", default=None)
    p_run.add_argument("--full", action="store_true", help="also the informative runs of the report")
    p_report = sub.add_parser("report")
    p_report.add_argument("--padsim", required=True)
    p_report.add_argument("--output", required=True)
    p_report.add_argument("--workdir", default=None)
    p_report.add_argument("--built-from", default=None,
                          help="what the padsim binary was built from (default: this checkout's HEAD)")
    args = parser.parse_args()

    if args.command == "list":
        names = list(KNOWN_FAILURES) if args.known_failures else all_case_names()
        print("\n".join(names))
        return 0
    # Absolute: the bad-input runs happen in invalid/ (so that diagnostics name the bare file).
    workdir = Path(args.workdir or (Path(os.environ.get("TMPDIR", "/tmp")) / f"padsim-robustness-{os.getpid()}")).resolve()
    if args.command == "run":
        c = run_case(args.case, Path(args.padsim).resolve(), workdir, args.full)
        for cmd in c.commands:
            print("$ " + cmd)
        for ok, text in c.criteria:
            print(("ok    " if ok else "FAIL  ") + text)
        for f in c.figures:
            print("      " + f)
        if args.case in KNOWN_FAILURES:
            print(f"known failure: {KNOWN_FAILURES[args.case]}")
        return 0 if passed(c) else 1
    start = time.monotonic()
    results = []
    for name in all_case_names():
        c = run_case(name, Path(args.padsim).resolve(), workdir, full=True)
        print(f"{'pass' if passed(c) else 'FAIL'}  {name}", file=sys.stderr)
        results.append(c)
    write_report(results, args.output, args.built_from or git_description(), time.monotonic() - start)
    print(f"wrote {args.output}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
