#include "mna/waveform.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "mna/device.hpp"

namespace mna {

namespace {

// PULSE(V1 V2 TD TR TF PW PER NP), SIN(VO VA FREQ TD THETA PHASE), EXP(V1 V2 TD1 TAU1 TD2 TAU2)
std::vector<double> with_defaults(Waveform::Shape shape, std::vector<double> p, const RunSettings& run,
                                  const std::string& element) {
  const double tstep = run.tstep > 0 ? run.tstep : run.tstop / 50;
  auto fill = [&](std::size_t count, std::size_t minimum) {
    if (p.size() < minimum || p.size() > count)
      throw ModelError("element '" + element + "': source function expects " + std::to_string(minimum) +
                       " to " + std::to_string(count) + " parameters, got " + std::to_string(p.size()));
    p.resize(count, std::nan(""));
  };
  auto given = [&](std::size_t i) { return !std::isnan(p[i]); };
  switch (shape) {
    case Waveform::Shape::constant: break;
    case Waveform::Shape::pulse:
      fill(8, 2);
      if (!given(2)) p[2] = 0;
      // ngspice (vsrcload.c): a zero or omitted rise/fall time means TSTEP, a zero or omitted
      // width or period TSTOP.
      if (!given(3) || p[3] == 0) p[3] = tstep;
      if (!given(4) || p[4] == 0) p[4] = tstep;
      if (!given(5) || p[5] == 0) p[5] = run.tstop;
      if (!given(6) || p[6] == 0) p[6] = run.tstop;
      if (!given(7)) p[7] = 0;  // number of pulses, 0: unlimited
      break;
    case Waveform::Shape::sine:
      fill(6, 2);
      if (!given(2) || p[2] == 0) p[2] = run.tstop > 0 ? 1 / run.tstop : 0;
      for (int i : {3, 4, 5})
        if (!given(i)) p[i] = 0;
      break;
    case Waveform::Shape::exponential:
      fill(6, 2);
      if (!given(2)) p[2] = 0;
      if (!given(3) || p[3] == 0) p[3] = tstep;
      if (!given(4) || p[4] == 0) p[4] = p[2] + tstep;
      if (!given(5) || p[5] == 0) p[5] = tstep;
      break;
    case Waveform::Shape::frequency_modulated:
      // SFFM(VO VA FC MDI FS PHASEC PHASES), phases in degrees (ngspice 38); FC and FS 1/TSTOP
      // when omitted or zero.
      fill(7, 2);
      for (int i : {2, 4})
        if (!given(i) || p[i] == 0) p[i] = run.tstop > 0 ? 1 / run.tstop : 0;
      for (int i : {3, 5, 6})
        if (!given(i)) p[i] = 0;
      break;
    case Waveform::Shape::piecewise_linear:
      if (p.size() < 2 || p.size() % 2 != 0)
        throw ModelError("element '" + element + "': PWL needs time-value pairs");
      for (std::size_t i = 2; i < p.size(); i += 2)
        if (p[i] < p[i - 2])
          throw ModelError("element '" + element + "': PWL times must not decrease");
      break;
  }
  return p;
}

}  // namespace

// The corners of the pulse period that contains t (the first period before TD, the last one
// after NP pulses); a period start itself belongs to the period before when `left` (the value
// there is the left limit, which matters when PW or PER cut the pulse short and it jumps).
// value() and next_corner() both use these very numbers, so that the integrator, which lands
// exactly on a corner, and the function agree on which side it is.
SourceFunction::PulseCorners SourceFunction::pulse_corners(double t, bool left) const {
  // Strictly inside a period both sides agree on it.
  if (last_period_ && t > last_period_->rise_start && t < last_period_->next_period) return *last_period_;
  last_period_ = compute_pulse_corners(t, left);
  return *last_period_;
}

SourceFunction::PulseCorners SourceFunction::compute_pulse_corners(double t, bool left) const {
  const double td = p_[2], tr = p_[3], tf = p_[4], pw = p_[5], per = p_[6], count = p_[7];
  auto start_of = [&](double k) { return td + k * per; };
  double k = t <= td ? 0 : std::floor((t - td) / per);
  if (k > 0 && start_of(k) > t) --k;  // floor's rounding against the start as computed here
  if (start_of(k + 1) <= t) ++k;
  if (left && k > 0 && start_of(k) == t) --k;
  if (count > 0 && k > count - 1) k = count - 1;
  const double start = start_of(k), next = count > 0 && k + 1 >= count ? infinity : start_of(k + 1);
  // A period's corners never pass the next period's start, and one within round-off of it is it
  // (tr + pw + tf = PER computed two ways differs by ulps: no step should have to fit between).
  auto corner = [&](double c) { return next - c <= 1e-9 * per ? next : c; };
  return {start, corner(start + tr), corner(start + tr + pw), corner(start + tr + pw + tf), next};
}

SourceFunction::SourceFunction(const Waveform& waveform, double dc_value, const RunSettings& run,
                               const std::string& element)
    : shape_(waveform.shape), p_(with_defaults(waveform.shape, waveform.parameters, run, element)), dc_(dc_value) {
  // r= the last time point repeats nothing: the function holds its last value, as without r=.
  if (waveform.repeat_from && *waveform.repeat_from < p_[p_.size() - 2]) {
    repeat_from_ = waveform.repeat_from;
    repeat_period_ = p_[p_.size() - 2] - *repeat_from_;
    while (2 * repeat_first_point_ + 2 < p_.size() && p_[2 * repeat_first_point_ + 2] <= *repeat_from_)
      ++repeat_first_point_;
  }
}

double SourceFunction::value(double t) const {
  using std::numbers::pi;
  switch (shape_) {
    case Waveform::Shape::constant: return dc_;
    case Waveform::Shape::pulse: {
      const double v1 = p_[0], v2 = p_[1];
      const PulseCorners c = pulse_corners(t, true);
      if (t <= c.rise_start) return v1;
      if (t < c.rise_end) return v1 + (v2 - v1) * (t - c.rise_start) / (c.rise_end - c.rise_start);
      if (t <= c.fall_start) return v2;
      if (t < c.fall_end) return v2 + (v1 - v2) * (t - c.fall_start) / (c.fall_end - c.fall_start);
      return v1;
    }
    case Waveform::Shape::sine: {
      const double vo = p_[0], va = p_[1], freq = p_[2], td = p_[3], theta = p_[4];
      const double phase = p_[5] * pi / 180;
      if (t <= td) return vo + va * std::sin(phase);
      return vo + va * std::sin(2 * pi * freq * (t - td) + phase) * std::exp(-(t - td) * theta);
    }
    case Waveform::Shape::exponential: {
      const double v1 = p_[0], v2 = p_[1], td1 = p_[2], tau1 = p_[3], td2 = p_[4], tau2 = p_[5];
      // Nothing moves before TD1, the fall included (ngspice's vsrcload.c): with TD2 < TD1 the
      // value holds V1 up to TD1, then jumps to where both terms are.
      if (t <= td1) return v1;
      double v = v1 + (v2 - v1) * (1 - std::exp(-(t - td1) / tau1));
      if (t > td2) v += (v1 - v2) * (1 - std::exp(-(t - td2) / tau2));
      return v;
    }
    case Waveform::Shape::frequency_modulated: {
      const double vo = p_[0], va = p_[1], fc = p_[2], mdi = p_[3], fs = p_[4];
      const double phase_carrier = p_[5] * pi / 180, phase_signal = p_[6] * pi / 180;
      return vo + va * std::sin(2 * pi * fc * t + phase_carrier + mdi * std::sin(2 * pi * fs * t + phase_signal));
    }
    case Waveform::Shape::piecewise_linear: return pwl_value(t);
  }
  return dc_;
}

// Repetition j of a PWL with r= spans (start(j), start(j + 1)], start(j) = last + j P: its time
// points are those after r, shifted by start(j) - r. value() and next_corner() compute them by
// the very same expressions, so that at a corner the integrator lands on both agree on the side
// (the left limit), also where the function jumps there.
double SourceFunction::repetition_start(double j) const { return p_[p_.size() - 2] + j * repeat_period_; }

double SourceFunction::repetition_index(double t) const {
  double j = std::floor((t - p_[p_.size() - 2]) / repeat_period_);
  if (repetition_start(j) >= t) --j;
  if (repetition_start(j + 1) < t) ++j;
  return j;
}

double SourceFunction::repetition_time(std::size_t point, double j) const {
  const double time = p_[2 * point];
  if (point + 1 == p_.size() / 2) return repetition_start(j + 1);
  return repetition_start(j) + (time - *repeat_from_);
}

double SourceFunction::pwl_value(double t) const {
  const std::size_t n = p_.size() / 2;
  const bool repeating = repeat_from_ && t > p_[2 * n - 2];
  // The points of the first pass, or those of the repetition that contains t.
  const std::size_t first = repeating ? repeat_first_point_ : 0;
  const double j = repeating ? repetition_index(t) : 0;
  auto time_of = [&](std::size_t k) { return repeating ? repetition_time(k, j) : p_[2 * k]; };
  if (t <= time_of(first)) return p_[2 * first + 1];
  for (std::size_t k = first + 1; k < n; ++k) {
    const double t0 = time_of(k - 1), t1 = time_of(k);
    if (t <= t1) {
      if (t1 == t0) return p_[2 * k + 1];
      return p_[2 * k - 1] + (p_[2 * k + 1] - p_[2 * k - 1]) * (t - t0) / (t1 - t0);
    }
  }
  return p_[2 * n - 1];
}

double SourceFunction::pwl_next_corner(double t) const {
  const std::size_t n = p_.size() / 2;
  for (std::size_t k = 0; k < n; ++k)
    if (p_[2 * k] > t) return p_[2 * k];
  if (!repeat_from_) return infinity;
  // t is at most the end of its repetition: the next corner is in it or in the one after.
  const double j = repetition_index(t);
  for (double repetition : {j, j + 1})
    for (std::size_t k = 0; k < n; ++k)
      if (p_[2 * k] > *repeat_from_ && repetition_time(k, repetition) > t) return repetition_time(k, repetition);
  return infinity;
}

// Only at a corner (the first one after the double before t is t itself). PWL and PULSE are
// linear between corners: the right limit at t is the line through the next piece's midpoint
// and end (the function is constant after its last corner). The others are continuous.
bool SourceFunction::jumps_at(double t) const {
  // An EXP whose fall began before its rise (TD2 < TD1) jumps at TD1 to where both terms are.
  if (shape_ == Waveform::Shape::exponential) return t == p_[2] && p_[4] < p_[2] && p_[0] != p_[1];
  if (shape_ != Waveform::Shape::piecewise_linear && shape_ != Waveform::Shape::pulse) return false;
  if (next_corner(std::nextafter(t, -infinity)) != t) return false;
  const double next = next_corner(t);
  const double end = std::isinf(next) ? t + 1 + std::abs(t) : next;
  const double middle = value(t + (end - t) / 2), at_end = value(end);
  const double right = std::isinf(next) ? at_end : 2 * middle - at_end;
  // Beyond the rounding of the extrapolation: of the values, and of the times (the slope times
  // a few ulps of t).
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const double slope = std::isinf(next) ? 0 : std::abs(at_end - middle) / ((end - t) / 2);
  return std::abs(right - value(t)) > 64 * eps * (std::abs(middle) + std::abs(at_end) + slope * std::abs(t));
}

double SourceFunction::resolution_step() const {
  if (shape_ == Waveform::Shape::sine && p_[2] > 0) return 1 / (20 * p_[2]);
  // An SFFM's instantaneous frequency reaches FC + MDI FS.
  const double highest = shape_ == Waveform::Shape::frequency_modulated ? p_[2] + std::abs(p_[3]) * p_[4] : 0;
  return highest > 0 ? 1 / (20 * highest) : infinity;
}

double SourceFunction::next_corner(double t) const {
  switch (shape_) {
    case Waveform::Shape::constant: return infinity;
    case Waveform::Shape::pulse: {
      auto first_after = [t](const PulseCorners& c) {
        for (double corner : {c.rise_start, c.rise_end, c.fall_start, c.fall_end})
          if (corner > t) return corner;
        return infinity;
      };
      const PulseCorners here = pulse_corners(t, false);
      const double in_this_period = first_after(here);
      // The next period only when this one has no corner left: looking it up replaces the period
      // kept (last_period_).
      return in_this_period < infinity ? in_this_period : first_after(pulse_corners(here.next_period, false));
    }
    case Waveform::Shape::sine: return p_[3] > t ? p_[3] : infinity;
    case Waveform::Shape::exponential:
      if (p_[2] > t) return p_[2];
      return p_[4] > t ? p_[4] : infinity;
    case Waveform::Shape::frequency_modulated: return infinity;
    case Waveform::Shape::piecewise_linear: return pwl_next_corner(t);
  }
  return infinity;
}

}  // namespace mna
