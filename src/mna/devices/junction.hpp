// What the pn junctions (D, and a MOSFET's bulk junctions) share: SPICE's depletion charge and
// pnjlim's limit on Newton's steps into forward conduction.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace mna::junction {

constexpr double boltzmann = 1.38064852e-23;  // ngspice 39 const.h
constexpr double charge = 1.6021766208e-19;
constexpr double nominal_temperature = 300.15;  // 27 C
constexpr double nominal_thermal_voltage = boltzmann * nominal_temperature / charge;
constexpr double gmin = 1e-12;  // ngspice's conductance across every junction
constexpr double largest_exponent = 40;
constexpr double largest_current = 1e3;  // amperes: no junction here carries more

// Where a junction of this saturation current continues its exponential linearly (value and
// slope matching): at largest_current or at largest_exponent thermal voltages, whichever comes
// first. A Newton step may land at huge forward voltages (modified Newton on a held matrix): f
// stays smooth and finite there, and solutions below that current are the same.
inline double exponent_limit(double saturation_current) {
  return std::min(largest_exponent, std::log(largest_current / saturation_current));
}

// exp(x) and its slope, continued linearly above `limit`.
inline std::pair<double, double> limited_exp(double x, double limit) {
  if (x <= limit) {
    const double e = std::exp(x);
    return {e, e};
  }
  const double e = std::exp(limit);
  return {e * (1 + x - limit), e};
}

// Depletion charge and capacitance of a junction with zero-bias capacitance c0, potential vj
// and grading m: SPICE's power law below fc vj, the capacitance extrapolated linearly above.
inline std::pair<double, double> depletion_charge(double v, double c0, double vj, double m, double fc) {
  if (c0 == 0) return {0, 0};
  if (v < fc * vj) {
    const double arg = 1 - v / vj, sarg = std::exp(-m * std::log(arg));
    return {vj * c0 * (1 - arg * sarg) / (1 - m), c0 * sarg};
  }
  const double f1 = vj * (1 - std::pow(1 - fc, 1 - m)) / (1 - m);
  const double f2 = std::pow(1 - fc, 1 + m), f3 = 1 - fc * (1 + m);
  const double q = c0 * f1 + c0 / f2 * (f3 * (v - fc * vj) + m / (2 * vj) * (v * v - fc * vj * fc * vj));
  return {q, c0 / f2 * (f3 + m * v / vj)};
}

// pnjlim's critical voltage, where the current-voltage curve bends most sharply (its radius of
// curvature is least). At least vt, so that the limit below stays a forward voltage for any
// saturation current.
inline double critical_voltage(double vt, double saturation_current) {
  return std::max(vt, vt * std::log(vt / (std::numbers::sqrt2 * saturation_current)));
}

// The fraction of a step from v to v_next along an exponential exp(v / vt) that pnjlim (in its
// Berkeley form) lets through: a step more than 2 vt forward that ends past the critical voltage
// stops where the current has grown by the factor the linearization at v promised,
// vt ln(v_next / vt) from reverse bias and v + vt ln(1 + (v_next - v) / vt) from forward bias.
inline double step_fraction(double v, double v_next, double vt, double v_critical) {
  if (!(v_next > v_critical && v_next - v > 2 * vt)) return 1;
  const double limited = v > 0 ? v + vt * std::log1p((v_next - v) / vt) : vt * std::log(v_next / vt);
  return (limited - v) / (v_next - v);
}

// SPICE's device convergence test (DIOconvTest): the current at v_after against its linearization
// at v_before, current(v) giving the current and its slope.
template <class Current>
bool current_converged(Current current, double v_before, double v_after, double rtol, double abstol) {
  const auto [before, slope] = current(v_before);
  const double predicted = before + slope * (v_after - v_before), after = current(v_after).first;
  return std::abs(after - predicted) <= rtol * std::max(std::abs(predicted), std::abs(after)) + abstol;
}

// The energy in a junction's charge at voltage v: the integral of u C(u) du from 0 to v
// (composite Simpson; only evaluated at events, for the jump energy balance).
template <class Capacitance>
double charge_energy(double v, Capacitance capacitance) {
  constexpr int intervals = 256;
  const double h = v / intervals;
  auto integrand = [&](double u) { return u * capacitance(u); };
  double sum = integrand(0) + integrand(v);
  for (int k = 1; k < intervals; ++k) sum += (k % 2 ? 4 : 2) * integrand(k * h);
  return sum * h / 3;
}

}  // namespace mna::junction
