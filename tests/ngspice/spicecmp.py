"""padsim-versus-ngspice comparison library (Python 3 standard library only).

Pieces, each unit-tested in test_spicecmp.py:
  - netlist reading: the .tran card (engineering suffixes, continuation lines);
  - ngspice batch runs: a generated control deck (wrdata with one time column), failure
    detection (ngspice exits 0 after "Timestep too small": the last time point must reach tstop);
  - padsim runs: `padsim NETLIST -o out.csv --probe "P1,P2"`, CSV read back;
  - comparison: linear interpolation onto the reference's time points, max and RMS absolute
    difference divided by the reference signal's range, per probe; threshold-crossing instants
    (linear interpolation between the points on both sides) compared separately; the max error
    with a timing tolerance (tube_distance) so that an edge is not counted twice.
"""

import bisect
import csv
import io
import math
import os
import re
import subprocess
import time as _time

# ----------------------------------------------------------------------------------------------
# Netlist reading

_SUFFIXES = [("meg", 1e6), ("mil", 25.4e-6), ("t", 1e12), ("g", 1e9), ("k", 1e3), ("m", 1e-3),
             ("u", 1e-6), ("n", 1e-9), ("p", 1e-12), ("f", 1e-15), ("a", 1e-18)]
_NUMBER = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+)(?:e[+-]?\d+)?)([a-z]*)$")


def spice_number(text):
    """A SPICE number: 1k, 2.5u, 10meg, 1e-3, 3.3v (trailing unit letters are ignored)."""
    m = _NUMBER.match(text.strip().lower())
    if not m:
        raise ValueError("not a SPICE number: %r" % text)
    value, tail = float(m.group(1)), m.group(2)
    for suffix, scale in _SUFFIXES:
        if tail.startswith(suffix):
            return value * scale
    return value


def logical_lines(text):
    """The netlist's cards after the title: continuation lines joined, comments dropped."""
    lines = text.splitlines()[1:]  # line 1 is the title
    cards = []
    for line in lines:
        stripped = line.strip()
        if not stripped or stripped.startswith("*"):
            continue
        if stripped.startswith("+") and cards:
            cards[-1] += " " + stripped[1:]
        else:
            cards.append(stripped)
    return [re.split(r"\s;|\s\$", c)[0].strip() for c in cards]


class Tran:
    def __init__(self, step, stop, start=0.0, max_step=None, uic=False):
        self.step, self.stop, self.start, self.max_step, self.uic = step, stop, start, max_step, uic

    def card(self):
        fields = [".tran", repr(self.step), repr(self.stop)]
        if self.max_step is not None or self.start:
            fields.append(repr(self.start))
        if self.max_step is not None:
            fields.append(repr(self.max_step))
        if self.uic:
            fields.append("uic")
        return " ".join(fields)


def parse_tran(text):
    """The netlist's .tran card as a Tran; raises ValueError when there is none."""
    for card in logical_lines(text):
        words = card.split()
        if words and words[0].lower() == ".tran":
            args = [w for w in words[1:]]
            uic = any(a.lower() == "uic" for a in args)
            nums = [spice_number(a) for a in args if a.lower() != "uic"]
            if len(nums) < 2:
                raise ValueError(".tran needs tstep and tstop: %r" % card)
            return Tran(nums[0], nums[1], nums[2] if len(nums) > 2 else 0.0,
                        nums[3] if len(nums) > 3 else None, uic)
    raise ValueError("no .tran card")


# ----------------------------------------------------------------------------------------------
# ngspice

class SimulationFailure(Exception):
    """A simulator failed: nonzero exit, abort message, or the run stopped short of tstop."""


# Messages after which ngspice's results are not a completed transient, even with exit code 0.
NGSPICE_FAILURE_PATTERNS = [
    r"timestep too small", r"\baborted\b", r"singular matrix", r"\bsingular\b",
    r"simulation\(s\) aborted", r"doanalyses:", r"tran simulation\(s\) aborted",
    r"fatal", r"no such vector", r"unknown model", r"unable to find definition",
    r"error on line", r"could not find", r"circuit not parsed",
]


def scan_ngspice_log(log):
    """The first failure message found in ngspice's output, or None."""
    lower = log.lower()
    for pattern in NGSPICE_FAILURE_PATTERNS:
        m = re.search(pattern, lower)
        if m:
            start = lower.rfind("\n", 0, m.start()) + 1
            end = lower.find("\n", m.end())
            return log[start:end if end >= 0 else len(log)].strip()
    return None


def check_reached_tstop(times, tstop, who="ngspice"):
    if not times:
        raise SimulationFailure("%s wrote no time points" % who)
    if times[-1] < tstop * (1 - 1e-9) - 1e-18:
        raise SimulationFailure("%s stopped at t = %.9g, before tstop = %.9g" % (who, times[-1], tstop))


def strip_control(text):
    """The netlist without its .control ... .endc blocks and without .end (to append our own)."""
    out, in_control = [], False
    for line in text.splitlines():
        low = line.strip().lower()
        if low.startswith(".control"):
            in_control = True
            continue
        if in_control:
            if low.startswith(".endc"):
                in_control = False
            continue
        if low == ".end":
            continue
        out.append(line)
    return "\n".join(out) + "\n"


def replace_tran(text, tran):
    """The netlist with its .tran card replaced (single-line .tran cards only)."""
    lines, done = text.splitlines(), False
    for k, line in enumerate(lines):
        if k > 0 and line.strip().lower().startswith(".tran"):
            lines[k] = tran.card()
            done = True
    if not done:
        raise ValueError("no .tran card to replace")
    return "\n".join(lines) + "\n"


# Settings of ngspice's "tight" run, the reference that measures ngspice's own error floor.
# Newton tolerances follow reltol down (vntol 1e-9 V, abstol 1e-14 A) so that reltol governs;
# gear, because trapezoidal rings after a switch. The maximum step is set per case (run_regression).
TIGHT_OPTIONS = "reltol=1e-7 abstol=1e-14 vntol=1e-9 method=gear"
# padsim's reltol when neither the netlist nor --rtol gives one (src/cli/command.cpp, kDefaultRtol).
PADSIM_DEFAULT_RTOL = 1e-8


def ngspice_deck(netlist_text, probes, data_path, options="", max_step=None, accounting=True):
    """A batch deck: the netlist, optional .options and .tran max step, and a control block that
    runs the transient and writes the probes with wrdata (one time column, a header)."""
    text = strip_control(netlist_text)
    if max_step is not None:
        tran = parse_tran(netlist_text)
        tran.max_step = max_step if tran.max_step is None else min(tran.max_step, max_step)
        text = replace_tran(text, tran)
    if options:
        text += ".options %s\n" % options
    control = [".control", "set wr_singlescale", "set wr_vecnames", "option numdgt=12", "run"]
    if accounting:
        control.append("rusage all")
    control += ["wrdata %s %s" % (data_path, " ".join(probes)), "quit", ".endc", ".end"]
    return text + "\n".join(control) + "\n"


def read_wrdata(path):
    """wrdata output (wr_singlescale, wr_vecnames): ({name: column}, time column first)."""
    with open(path) as f:
        header = f.readline().split()
        columns = [[] for _ in header]
        for line in f:
            fields = line.split()
            if len(fields) != len(header):
                continue
            for c, field in enumerate(fields):
                columns[c].append(float(field))
    return header, columns


class Waveforms:
    """Time points and one list of values per probe (probe names as given, lower case)."""

    def __init__(self, time, signals, seconds=None, log="", stats=None):
        self.time, self.signals, self.seconds, self.log = time, signals, seconds, log
        self.stats = stats or {}


def parse_rusage(log):
    stats = {}
    for key, pattern in (("accepted", r"accepted timepoints\s*=\s*([\d.]+)"),
                         ("rejected", r"rejected timepoints\s*=\s*([\d.]+)"),
                         ("analysis_seconds", r"transient time\s*=\s*([\d.eE+-]+)"),
                         ("iterations", r"transient iterations\s*=\s*([\d.]+)")):
        m = re.search(pattern, log, re.IGNORECASE)
        if m:
            stats[key] = float(m.group(1))
    return stats


def run_ngspice(netlist_path, probes, workdir, options="", max_step=None, ngspice="ngspice",
                timeout=600, tag="ngspice"):
    """Runs ngspice -b on the netlist; returns Waveforms or raises SimulationFailure."""
    with open(netlist_path) as f:
        text = f.read()
    tran = parse_tran(text)
    os.makedirs(workdir, exist_ok=True)
    data = os.path.join(workdir, tag + ".data")
    deck = os.path.join(workdir, tag + ".cir")
    if os.path.exists(data):
        os.remove(data)
    with open(deck, "w") as f:
        f.write(ngspice_deck(text, probes, data, options, max_step))
    start = _time.monotonic()
    try:
        proc = subprocess.run([ngspice, "-b", deck], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              timeout=timeout, cwd=os.path.dirname(os.path.abspath(netlist_path)))
    except subprocess.TimeoutExpired:
        raise SimulationFailure("%s timed out after %g s" % (tag, timeout))
    seconds = _time.monotonic() - start
    log = proc.stdout.decode(errors="replace")
    with open(os.path.join(workdir, tag + ".log"), "w") as f:
        f.write(log)
    if proc.returncode != 0:
        raise SimulationFailure("%s exited with %d: %s" % (tag, proc.returncode, scan_ngspice_log(log) or log[-500:]))
    failure = scan_ngspice_log(log)
    if failure:
        raise SimulationFailure("%s: %s" % (tag, failure))
    if not os.path.exists(data):
        raise SimulationFailure("%s wrote no data file" % tag)
    header, columns = read_wrdata(data)
    if len(header) != len(probes) + 1:
        raise SimulationFailure("%s wrote columns %s for probes %s" % (tag, header, probes))
    check_reached_tstop(columns[0], tran.stop, tag)
    signals = {p.lower(): columns[k + 1] for k, p in enumerate(probes)}
    return Waveforms(columns[0], signals, seconds, log, parse_rusage(log))


# ----------------------------------------------------------------------------------------------
# padsim

def read_csv(path):
    """padsim's CSV: header "time,<probes>" (quoted names allowed), then numbers.
    Returns (names in lower case, columns). A last line without its newline (a killed run) is
    ignored."""
    with open(path, newline="") as f:
        text = f.read()
    if not text.endswith("\n"):
        text = text[:text.rfind("\n") + 1]
    rows = csv.reader(io.StringIO(text))
    header = [h.strip().lower().replace(" ", "") for h in next(rows)]
    columns = [[] for _ in header]
    for fields in rows:
        if len(fields) != len(header):
            continue
        for c, field in enumerate(fields):
            columns[c].append(float(field))
    return header, columns


def padsim_command(padsim, netlist, csv_path, probes, extra=()):
    """padsim NETLIST -o CSV --probe "p1,p2,..." [extra...] (the probe list is one argument)."""
    return [padsim, netlist, "-o", csv_path, "--probe", ",".join(probes)] + list(extra)


def run_padsim(padsim, netlist_path, probes, workdir, extra=(), timeout=600):
    with open(netlist_path) as f:
        tran = parse_tran(f.read())
    os.makedirs(workdir, exist_ok=True)
    csv_path = os.path.join(workdir, "padsim.csv")
    if os.path.exists(csv_path):
        os.remove(csv_path)
    cmd = padsim_command(padsim, netlist_path, csv_path, probes, extra)
    start = _time.monotonic()
    try:
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise SimulationFailure("padsim timed out after %g s" % timeout)
    seconds = _time.monotonic() - start
    log = proc.stdout.decode(errors="replace")
    if proc.returncode != 0:
        raise SimulationFailure("padsim exited with %d: %s" % (proc.returncode, log[-2000:]))
    header, columns = read_csv(csv_path)
    if header[0] != "time":
        raise SimulationFailure("padsim CSV has no time column: %s" % header)
    signals = {}
    for p in probes:
        if p.lower() not in header:
            raise SimulationFailure("padsim CSV lacks probe %s (columns %s)" % (p, header))
        signals[p.lower()] = columns[header.index(p.lower())]
    check_reached_tstop(columns[0], tran.stop, "padsim")
    return Waveforms(columns[0], signals, seconds, log)


# ----------------------------------------------------------------------------------------------
# Comparison

def interpolate(t_src, y_src, t_query):
    """Piecewise-linear interpolation of (t_src, y_src) at the sorted times t_query.

    t_src is non-decreasing; where it repeats a time (a jump recorded as left and right limits),
    a query exactly at that time takes the right limit (the last sample), and queries just before
    and after interpolate on the proper side. Outside the range the end values are held."""
    n = len(t_src)
    if n == 0:
        raise ValueError("empty waveform")
    out, k = [], 0
    for t in t_query:
        # advance k to the last index with t_src[k] <= t
        while k + 1 < n and t_src[k + 1] <= t:
            k += 1
        if t <= t_src[0] and not (t == t_src[0] and k > 0):
            out.append(y_src[0] if t < t_src[0] else y_src[k])
        elif k + 1 >= n:
            out.append(y_src[-1])
        else:
            t0, t1 = t_src[k], t_src[k + 1]
            if t1 == t0:
                out.append(y_src[k + 1])
            else:
                w = (t - t0) / (t1 - t0)
                out.append(y_src[k] + w * (y_src[k + 1] - y_src[k]))
    return out


def crossing_brackets(t, y, threshold, hysteresis=0.0):
    """Threshold crossings as (time, direction, t_before, t_after): direction +1 (rising) or -1
    (falling); time by linear interpolation between the samples on both sides of the threshold,
    which are at t_before and t_after (equal for a jump recorded as two rows at one time).

    With hysteresis h, a crossing counts only once the signal has gone from below threshold - h
    to above threshold + h (or back), so ringing around the threshold gives one crossing; the time
    reported is that of the last threshold passage before the band was left."""
    found = []
    state = None  # +1 above the band, -1 below
    last_pass = None  # (time, direction, t_before, t_after) of the latest threshold passage
    for k in range(len(t)):
        if k > 0:
            a, b = y[k - 1] - threshold, y[k] - threshold
            if (a < 0 <= b) or (a >= 0 > b):
                tc = t[k - 1] if b == a else t[k - 1] + (t[k] - t[k - 1]) * (-a / (b - a))
                last_pass = (tc, 1 if b >= 0 else -1, t[k - 1], t[k])
        if y[k] > threshold + hysteresis:
            if state == -1 and last_pass is not None:
                found.append(last_pass[:1] + (1,) + last_pass[2:])
            state = 1
        elif y[k] < threshold - hysteresis:
            if state == 1 and last_pass is not None:
                found.append(last_pass[:1] + (-1,) + last_pass[2:])
            state = -1
    return found


def crossings(t, y, threshold, hysteresis=0.0):
    """Threshold crossings as (time, direction); see crossing_brackets."""
    return [c[:2] for c in crossing_brackets(t, y, threshold, hysteresis)]


def signal_range(y):
    r = max(y) - min(y)
    return r if r > 0 else max(abs(max(y)), 1e-30)


def tube_distance(t_ref, y_ref, t_test, y_test, tau):
    """For each reference point (t, y): the distance from y to the values the test waveform
    (piecewise linear) takes within [t - tau, t + tau]; 0 when y is among them. tau = 0 gives the
    plain |test(t) - y|. An edge that the test places up to tau away from the reference's costs
    nothing; anything else does. tau: one value, or one per reference point."""
    taus = tau if isinstance(tau, list) else [tau] * len(t_ref)
    if max(taus, default=0.0) <= 0:
        return [abs(a - b) for a, b in zip(interpolate(t_test, y_test, t_ref), y_ref)]
    left = interpolate(t_test, y_test, [t - w for t, w in zip(t_ref, taus)])
    right = interpolate(t_test, y_test, [t + w for t, w in zip(t_ref, taus)])
    out, n = [], len(t_test)
    for k, t in enumerate(t_ref):
        w = taus[k]
        lo, hi = min(left[k], right[k]), max(left[k], right[k])
        i = bisect.bisect_right(t_test, t - w)
        while i < n and t_test[i] < t + w:
            v = y_test[i]
            if v < lo:
                lo = v
            elif v > hi:
                hi = v
            i += 1
        y = y_ref[k]
        out.append(lo - y if y < lo else (y - hi if y > hi else 0.0))
    return out


def jump_slack(t_jumping, t_other):
    """Per point of a waveform that records jumps as two rows at one time: at a jump row, the
    width of the other waveform's sampling interval containing that time (where a jump lies
    inside one sampling interval of the other simulator is unknowable: its linear interpolation
    there is a ramp); 0 elsewhere."""
    slack, n = [], len(t_jumping)
    for k, t in enumerate(t_jumping):
        at_jump = (k > 0 and t_jumping[k - 1] == t) or (k + 1 < n and t_jumping[k + 1] == t)
        j = bisect.bisect_right(t_other, t)
        inside = 0 < j < len(t_other)
        slack.append(t_other[j] - t_other[j - 1] if at_jump and inside else 0.0)
    return slack


def waveform_error(t_ref, y_ref, t_test, y_test, tau=0.0):
    """(max, rms) of the test waveform's error on the reference's time points, divided by the
    reference's range. RMS: |test(t) - ref(t)|, time-weighted (trapezoid over the reference's
    non-uniform points). Max: the tube distance with time tolerance tau (see tube_distance), in
    both directions (reference points against the test, test points against the reference); a
    test point at a jump also tolerates the reference's sampling interval around it
    (jump_slack)."""
    y_int = interpolate(t_test, y_test, t_ref)
    scale = signal_range(y_ref)
    diffs = [abs(a - b) for a, b in zip(y_int, y_ref)]
    # Both ways: every reference point near the test's values and every test point near the
    # reference's, so neither an edge nor a spike of either one is lost.
    test_tau = [tau + s for s in jump_slack(t_test, t_ref)]
    max_err = max(max(tube_distance(t_ref, y_ref, t_test, y_test, tau)),
                  max(tube_distance(t_test, y_test, t_ref, y_ref, test_tau))) / scale
    total, acc = t_ref[-1] - t_ref[0], 0.0
    for k in range(1, len(t_ref)):
        acc += 0.5 * (diffs[k] ** 2 + diffs[k - 1] ** 2) * (t_ref[k] - t_ref[k - 1])
    rms = math.sqrt(acc / total) / scale if total > 0 else 0.0
    return max_err, rms


def match_crossings(ref, test):
    """Pairs each reference crossing with the unused test crossing of the same direction nearest
    in time. Returns (max |dt|, list of (ref index, test index), unmatched reference count,
    surplus test count)."""
    pairs, used = [], set()
    for i, (tc, d) in enumerate(c[:2] for c in ref):
        best = None
        for j, c in enumerate(test):
            tt, dd = c[0], c[1]
            if dd != d or j in used:
                continue
            if best is None or abs(tt - tc) < abs(test[best][0] - tc):
                best = j
        if best is None:
            continue
        used.add(best)
        pairs.append((i, best))
    max_dt = max((abs(test[j][0] - ref[i][0]) for i, j in pairs), default=0.0)
    return max_dt, pairs, len(ref) - len(pairs), len(test) - len(pairs)


def compare(ref, test, probes, crossing=None, tau=None):
    """Compares Waveforms test against reference ref.

    crossing: optional list of (probe, threshold, hysteresis): the switching instants. Their
    crossings in both waveforms are matched one to one (direction, nearness) and the largest time
    difference reported; missing and extra crossings are counted.
    tau: the timing tolerance of the max error: an edge displaced by up to tau costs nothing in
    the max error (the displacement itself is the switching-instant check). None: tau = the
    measured largest switching-time difference (0 without crossings); the floor run measures
    ngspice's own this way, and the regression then uses that value for padsim. To tau is added
    the widest sampling step across a matched edge (in either waveform): the max error's time
    tolerance (see tube_distance) is tau plus that step. The RMS is pointwise, with no time
    tolerance.
    Returns {"probes": {probe: (max, rms)}, "tau": tau, "crossing": None or {"max_dt",
    "ref_count", "test_count", "unmatched", "surplus"}}."""
    result = {"probes": {}, "crossing": None}
    if crossing is not None:
        specs = crossing if isinstance(crossing, list) else [crossing]
        total = {"max_dt": 0.0, "ref_count": 0, "test_count": 0, "unmatched": 0, "surplus": 0,
                 "edge_step": 0.0}
        for name, threshold, hysteresis in specs:
            name = name.lower()
            cr = crossing_brackets(ref.time, ref.signals[name], threshold, hysteresis)
            ct = crossing_brackets(test.time, test.signals[name], threshold, hysteresis)
            max_dt, pairs, unmatched, surplus = match_crossings(cr, ct)
            total["max_dt"] = max(total["max_dt"], max_dt)
            total["ref_count"] += len(cr)
            total["test_count"] += len(ct)
            total["unmatched"] += unmatched
            total["surplus"] += surplus
            for i, j in pairs:
                total["edge_step"] = max(total["edge_step"], cr[i][3] - cr[i][2], ct[j][3] - ct[j][2])
        result["crossing"] = total
    if tau is None:
        tau = result["crossing"]["max_dt"] if result["crossing"] else 0.0
    if result["crossing"]:
        tau += result["crossing"]["edge_step"]
    result["tau"] = tau
    for p in probes:
        p = p.lower()
        result["probes"][p] = waveform_error(ref.time, ref.signals[p], test.time, test.signals[p], tau)
    return result
