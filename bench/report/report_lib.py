"""Pure helpers of the benchmark report (Python 3 standard library only), unit-tested in
test_report_lib.py: closed-form references, exact crossing instants, error evaluation on a grid,
Pareto fronts and time ratios at equal error, scaling exponents, medians.

The waveform machinery (interpolation, error metrics, threshold crossings) is spicecmp's, from
tests/ngspice; this module adds what the report needs on top of it.
"""
import bisect
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "ngspice"))
import spicecmp as sc  # noqa: E402


# ----------------------------------------------------------------------------------------------
# Closed forms

def _gauss5(f, mid, half):
    """Gauss-Legendre, 5 points, on [mid - half, mid + half] (exact for degree 9)."""
    nodes = (0.0, 0.5384693101056831, 0.9061798459386640)
    weights = (0.5688888888888889, 0.4786286704993665, 0.2369268850561891)
    total = weights[0] * f(mid)
    for x, w in zip(nodes[1:], weights[1:]):
        total += w * (f(mid - half * x) + f(mid + half * x))
    return total * half


def ramp_response(step, t, delay, rise):
    """Response of a linear time-invariant circuit at time t to an input that ramps from 0 to 1
    between delay and delay + rise (a SPICE PULSE edge): the step response averaged over the
    rise, (1/rise) * integral_{t - rise}^{t} step(tau - delay) dtau, with step = 0 before 0.
    (The window's width is taken as `rise` exactly, not as t - (t - rise), which rounds.)"""
    if t <= delay:
        return 0.0
    if t - delay >= rise:
        return _gauss5(lambda tau: step(tau - delay), t - 0.5 * rise, 0.5 * rise) / rise
    return _gauss5(lambda tau: step(tau), 0.5 * (t - delay), 0.5 * (t - delay)) / rise


class RlcStep:
    """circuits/rlc_step.cir: series R = 10, L = 1 mH, C = 1 uF driven by PULSE(0 1 50u 1n ...).
    v(out) across C, i(l1) the current through L (from a to out)."""

    def __init__(self, r=10.0, l=1e-3, c=1e-6, delay=50e-6, rise=1e-9):
        self.r, self.l, self.c, self.delay, self.rise = r, l, c, delay, rise
        self.alpha = r / (2 * l)
        self.w0 = 1 / math.sqrt(l * c)
        self.wd = math.sqrt(self.w0 ** 2 - self.alpha ** 2)

    def _v_step(self, tau):
        a, wd = self.alpha, self.wd
        return 1 - math.exp(-a * tau) * (math.cos(wd * tau) + a / wd * math.sin(wd * tau))

    def _i_step(self, tau):
        return self.c * math.exp(-self.alpha * tau) * self.w0 ** 2 / self.wd * math.sin(self.wd * tau)

    def __call__(self, t):
        return {"v(out)": ramp_response(self._v_step, t, self.delay, self.rise),
                "i(l1)": ramp_response(self._i_step, t, self.delay, self.rise)}


class RelaxationOscillator:
    """circuits/relaxation_oscillator.cir: ideal comparator out = +-5 V, thresholds out / 2,
    R1 C1 = 1 ms, v(cap)(0) = 3 V with out = -5 V. Edges at t1 = RC ln(8 / 2.5), then every
    RC ln 3."""

    def __init__(self, rc=1e-3, high=5.0, v0=3.0):
        self.rc, self.high, self.v0 = rc, high, v0
        self.t1 = rc * math.log((v0 + high) / (high / 2))
        self.half_period = rc * math.log(3.0)

    def edges(self, t_stop):
        """Edge instants up to t_stop, with their direction (+1: out goes to +5)."""
        out, t, k = [], self.t1, 0
        while t < t_stop:
            out.append((t, 1 if k % 2 == 0 else -1))
            k += 1
            t = self.t1 + k * self.half_period
        return out

    def __call__(self, t):
        h, rc = self.high, self.rc
        if t < self.t1:
            return {"v(cap)": -h + (self.v0 + h) * math.exp(-t / rc), "v(out)": -h}
        k = int((t - self.t1) // self.half_period)
        start = self.t1 + k * self.half_period
        out = h if k % 2 == 0 else -h
        # From -out/2 towards out: v = out - 1.5 out exp(-(t - start) / RC).
        return {"v(cap)": out - 1.5 * out * math.exp(-(t - start) / rc), "v(out)": out}


class StiffCascade:
    """circuits/stiff_cascade.cir: buffered RC lags tau = 1 ns, 1 us, 1 ms, 1 s driven by a
    1 V step with a 1 ns rise at t = 0. v(nk) = (1/rise) integral over the rise of the step
    response 1 - sum_j A_kj exp(-t / tau_j), A_kj = prod_{i <= k, i != j} tau_j / (tau_j - tau_i)."""

    def __init__(self, taus=(1e-9, 1e-6, 1e-3, 1.0), rise=1e-9):
        self.taus, self.rise = list(taus), rise
        self.coefficients = []
        for k in range(len(taus)):
            row = []
            for j in range(k + 1):
                a = 1.0
                for i in range(k + 1):
                    if i != j:
                        a *= taus[j] / (taus[j] - taus[i])
                row.append(a)
            self.coefficients.append(row)

    def stage(self, k, t):
        """v(n<k+1>) at t: the step response integrated in closed form over [max(0, t - rise), t]."""
        if t <= 0:
            return 0.0
        if t >= self.rise:
            # 1 + sum_j A_kj (tau_j / rise) exp(-(t - rise) / tau_j) expm1(-rise / tau_j)
            total = 1.0
            for tau, coef in zip(self.taus, self.coefficients[k]):
                total += coef * tau / self.rise * math.exp(-(t - self.rise) / tau) * math.expm1(-self.rise / tau)
            return total
        # (1 / rise) (t + sum_j A_kj tau_j expm1(-t / tau_j))
        total = t
        for tau, coef in zip(self.taus, self.coefficients[k]):
            total += coef * tau * math.expm1(-t / tau)
        return total / self.rise

    def __call__(self, t):
        return {"v(n%d)" % (k + 1): self.stage(k, t) for k in range(len(self.taus))}


# The Bari test set's TRANSAMP reference at t = 0.2 (node k = y_k), as in circuits/transistor_amplifier.cir
# and tests/padae/transistor_amplifier.hpp.
BARI_TRANSAMP = [-0.5562145012262709e-02, 0.3006522471903042e+01, 0.2849958788608128e+01,
                 0.2926422536206241e+01, 0.2704617865010554e+01, 0.2761837778393145e+01,
                 0.4770927631616772e+01, 0.1236995868091548e+01]


def bari_error(values):
    """The Bari test set's error measure at t = 0.2: max_k |y_k - ref_k| / (|ref_k| + 1)."""
    return max(abs(v - r) / (abs(r) + 1) for v, r in zip(values, BARI_TRANSAMP))


# ----------------------------------------------------------------------------------------------
# Grids, references and errors

def uniform_grid(t0, t1, n):
    return [t0 + (t1 - t0) * k / (n - 1) for k in range(n)]


def log_grid(first, last, n):
    """n points from first to last (> 0), equally spaced in log t."""
    a, b = math.log(first), math.log(last)
    return [math.exp(a + (b - a) * k / (n - 1)) for k in range(n)]


def merge_grids(*grids):
    return sorted(set(t for g in grids for t in g))


def sample(closed_form, grid, probes):
    """A closed form sampled on a grid, as spicecmp Waveforms."""
    signals = {p: [] for p in probes}
    for t in grid:
        values = closed_form(t)
        for p in probes:
            signals[p].append(values[p])
    return sc.Waveforms(list(grid), signals)


def exact_crossings(closed_form, probe, threshold, hysteresis, grid):
    """Threshold crossings of a closed form, with spicecmp's hysteresis rule applied to its
    samples on `grid`, each refined by bisection on the closed form to double precision."""
    ys = [closed_form(t)[probe] for t in grid]
    out = []
    for t, direction, lo, hi in sc.crossing_brackets(grid, ys, threshold, hysteresis):
        f = lambda s: closed_form(s)[probe] - threshold  # noqa: E731
        a, b = lo, hi
        fa = f(a)
        if fa == 0 or a == b:
            out.append((a, direction))
            continue
        for _ in range(200):
            m = 0.5 * (a + b)
            if m == a or m == b:
                break
            fm = f(m)
            if (fm < 0) == (fa < 0):
                a, fa = m, fm
            else:
                b = m
        out.append((0.5 * (a + b), direction))
    return out


def pointwise_error(times, values, reference_values, scale):
    """(max, rms) of |values - reference_values| / scale at a simulator's own output points;
    the RMS time-weighted (trapezoid over those points; two rows at one instant weigh nothing)."""
    diffs = [abs(a - b) for a, b in zip(values, reference_values)]
    if not diffs:
        return float("nan"), float("nan")
    acc = 0.0
    for k in range(1, len(times)):
        acc += 0.5 * (diffs[k] ** 2 + diffs[k - 1] ** 2) * (times[k] - times[k - 1])
    total = times[-1] - times[0]
    rms = math.sqrt(acc / total) if total > 0 else 0.0
    return max(diffs) / scale, rms / scale


class ClosedFormReference:
    """A closed form as the reference: evaluated at the simulator's own output points; each
    probe's range (the error's scale) from samples on `grid`."""

    def __init__(self, closed_form, probes, grid):
        self.closed_form, self.probes = closed_form, probes
        ref = sample(closed_form, grid, probes)
        self.scale = {p: sc.signal_range(ref.signals[p]) for p in probes}

    def errors(self, test):
        values = {p: [] for p in self.probes}
        for t in test.time:
            v = self.closed_form(t)
            for p in self.probes:
                values[p].append(v[p])
        return {p: pointwise_error(test.time, test.signals[p], values[p], self.scale[p]) for p in self.probes}


class RunReference:
    """A (dense) reference run: interpolated linearly onto the simulator's own output points."""

    def __init__(self, waveforms, probes):
        self.w, self.probes = waveforms, probes
        self.scale = {p: sc.signal_range(waveforms.signals[p]) for p in probes}

    def errors(self, test):
        return {p: pointwise_error(test.time, test.signals[p],
                                   sc.interpolate(self.w.time, self.w.signals[p], test.time), self.scale[p])
                for p in self.probes}


def match_crossings(ref, test):
    """Matches each reference crossing (time, direction) to the nearest unused test crossing of
    the same direction (spicecmp.match_crossings' rule, by bisection instead of a full scan, for
    thousands of crossings). Returns (list of |dt|, list of relative |dt| / t_ref, unmatched
    reference count, surplus test count)."""
    by_direction = {}
    for k, c in enumerate(test):
        by_direction.setdefault(c[1], []).append((c[0], k))
    times = {}
    for d, v in by_direction.items():
        v.sort()
        times[d] = [c[0] for c in v]
    used = set()
    dts, rel = [], []
    unmatched = 0
    for tr, d in ((c[0], c[1]) for c in ref):
        cands = by_direction.get(d, [])
        i = bisect.bisect_left(times.get(d, []), tr)
        lo, hi = i - 1, i
        while lo >= 0 and cands[lo][1] in used:
            lo -= 1
        while hi < len(cands) and cands[hi][1] in used:
            hi += 1
        best = None
        for j in (lo, hi):
            if 0 <= j < len(cands) and (best is None or abs(cands[j][0] - tr) < abs(cands[best][0] - tr)):
                best = j
        if best is None:
            unmatched += 1
            continue
        used.add(cands[best][1])
        dt = abs(cands[best][0] - tr)
        dts.append(dt)
        rel.append(dt / abs(tr) if tr else dt)
    return dts, rel, unmatched, len(test) - len(dts)


# ----------------------------------------------------------------------------------------------
# Work-precision arithmetic

def median(values):
    s = sorted(values)
    n = len(s)
    if n == 0:
        return float("nan")
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


def pareto_front(points):
    """(error, time) points -> the front: sorted by time, each strictly more accurate than every
    faster one. Non-finite or non-positive errors are dropped."""
    pts = sorted((t, e) for e, t in points if e > 0 and math.isfinite(e) and t > 0)
    front, best = [], float("inf")
    for t, e in pts:
        if e < best:
            front.append((e, t))
            best = e
    return front


def time_at_error(front, error):
    """The time a simulator needs for `error`, on its Pareto front, interpolated linearly in
    log(error)-log(time) between front points. None when the front never reaches `error`; when
    even the fastest run is more accurate than `error`, that run's time."""
    if not front:
        return None
    if error < front[-1][0]:
        return None
    if error >= front[0][0]:
        return front[0][1]
    for (e0, t0), (e1, t1) in zip(front, front[1:]):
        if e1 <= error <= e0:
            if e0 == e1:
                return t1
            w = (math.log(error) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0)))
    return None


def ratios_at_equal_error(front_a, front_b):
    """time_a / time_b at equal error, at the errors both reach (not below either front's most
    accurate run): at a's front points in that range, and at its lower end. Each time is
    interpolated log-log on its own front; above a front's least accurate run its fastest time
    holds (loosening cannot make a simulator faster than its fastest run).
    [(error, time_a, time_b, ratio)], empty when one never reaches the other's errors."""
    if not front_a or not front_b:
        return []
    lo = max(front_a[-1][0], front_b[-1][0])
    levels = sorted(set([lo] + [e for e, _ in front_a if e >= lo]), reverse=True)
    out = []
    for e in levels:
        ta, tb = time_at_error(front_a, e), time_at_error(front_b, e)
        if ta is not None and tb is not None:
            out.append((e, ta, tb, ta / tb))
    return out


def loglog_slope(xs, ys):
    """Least-squares slope of log y against log x."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    n = len(lx)
    mx, my = sum(lx) / n, sum(ly) / n
    sxx = sum((a - mx) ** 2 for a in lx)
    sxy = sum((a - mx) * (b - my) for a, b in zip(lx, ly))
    return sxy / sxx if sxx > 0 else float("nan")


def vntol_for(rtol):
    """The absolute voltage tolerance that goes with a relative tolerance in the sweeps: the
    simulators' default 1 uV at reltol 1e-3 and above, then 1e-3 x reltol (so that the
    absolute tolerance never dominates on volt-level signals)."""
    return min(1e-6, 1e-3 * rtol)


def fmt(x, digits=2):
    """A number for a table: 3 significant digits style, '-' for None/NaN."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    if x == 0:
        return "0"
    return "%.*g" % (digits, x)
