// D: the junction diode with ngspice's equations (level 1: IS, N, RS, CJO, VJ, M, FC, TT, BV,
// IBV, NBV, area), for regression against ngspice. The junction current, its charge and GMIN in
// parallel are loaded at the junction voltage; RS adds an internal node.
// Newton's steps into forward conduction (and into breakdown) are limited as ngspice's pnjlim
// limits them. Past the limit a step may still land at huge forward voltages (modified Newton on
// a held matrix): where the junction current would pass 1 kA (or at 40 thermal voltages,
// whichever comes first) the exponential continues linearly, value and slope matching, so f
// stays smooth and finite; solutions below that current are the same.
#include <cmath>
#include <numbers>
#include <optional>

#include "mna/device.hpp"

namespace mna {
namespace {

constexpr double boltzmann = 1.38064852e-23;   // ngspice 39 const.h
constexpr double charge = 1.6021766208e-19;
constexpr double nominal_temperature = 300.15; // 27 C
constexpr double gmin = 1e-12;
constexpr double largest_exponent = 40;
constexpr double largest_current = 1e3;  // amperes, before area: no diode here carries more

class Diode final : public Device {
 public:
  Diode(const ElementSpec& spec, const RunSettings& run) : Device(spec) {
    require_nodes(spec, 2);
    const double area = spec.area, vt = boltzmann * nominal_temperature / charge;
    saturation_current_ = parameter(spec, "is", 1e-14) * area;
    thermal_voltage_ = parameter(spec, "n", 1) * vt;
    breakdown_thermal_voltage_ = parameter(spec, "nbv", parameter(spec, "n", 1)) * vt;
    series_resistance_ = parameter(spec, "rs", 0) / area;
    junction_capacitance_ = parameter(spec, "cjo", parameter(spec, "cj0", 0)) * area;
    junction_potential_ = parameter(spec, "vj", 1);
    grading_ = parameter(spec, "m", 0.5);
    depletion_fraction_ = parameter(spec, "fc", 0.5);
    transit_time_ = parameter(spec, "tt", 0);
    if (!(saturation_current_ > 0) || !(thermal_voltage_ > 0) || !(breakdown_thermal_voltage_ > 0) || !(series_resistance_ >= 0) ||
        !(junction_potential_ > 0) || !(grading_ < 1) || !(depletion_fraction_ < 1))
      throw ModelError("diode '" + spec.name + "': parameters out of range (IS, N > 0, RS >= 0, VJ > 0, M < 1, FC < 1)");
    exponent_limit_ = std::min(largest_exponent, std::log(largest_current * area / saturation_current_));
    critical_voltage_ = critical_voltage(thermal_voltage_);
    critical_breakdown_voltage_ = critical_voltage(breakdown_thermal_voltage_);
    if (!(exponent_limit_ > 1)) throw ModelError("diode '" + spec.name + "': IS too large");
    if (auto bv = spec.model.find("bv"); bv != spec.model.end() && std::isfinite(bv->second))
      breakdown_voltage_ = breakdown_knee(bv->second, parameter(spec, "ibv", 1e-3) * area, vt, run.reltol);
  }

  void allocate(Unknowns& u) override {
    anode_ = u.node(card().nodes[0]), cathode_ = u.node(card().nodes[1]);
    junction_ = anode_;
    if (series_resistance_ > 0)
      junction_ = u.add("v(" + name() + "#internal)", UnknownCategory::internal_node, name());
  }
  void declare(Stamper& s) override {
    s.block(junction_, cathode_, junction_slots_);
    if (junction_capacitance_ > 0 || transit_time_ > 0) s.charge_block(junction_, cathode_, junction_slots_);
    if (series_resistance_ > 0) s.block(anode_, junction_, series_slots_);
  }
  void load(Evaluation& e) const override {
    const double v = e.value(junction_) - e.value(cathode_);
    const auto [current, conductance] = junction_current(v);
    const double i = current + gmin * v;
    e.f(junction_, i), e.f(cathode_, -i);
    const bool charged = junction_capacitance_ > 0 || transit_time_ > 0;
    double capacitance = 0;
    if (charged) {
      const auto [q, c] = junction_charge(v);
      const double total = q + transit_time_ * current;
      capacitance = c + transit_time_ * conductance;
      e.q(junction_, total), e.q(cathode_, -total);
    }
    if (series_resistance_ > 0) {
      const double g = 1 / series_resistance_, ir = g * (e.value(anode_) - e.value(junction_));
      e.f(anode_, ir), e.f(junction_, -ir);
      if (e.jacobian()) e.df(series_slots_, g);
    }
    if (!e.jacobian()) return;
    e.df(junction_slots_, conductance + gmin);
    if (charged) e.dq(junction_slots_, capacitance);
  }
  bool limits_newton_steps() const override { return true; }
  double newton_step_fraction(const Vector& x, const Vector& x_next) const override {
    const double v = junction_voltage(x), v_next = junction_voltage(x_next);
    double fraction = junction_step_fraction(v, v_next, thermal_voltage_, critical_voltage_);
    if (breakdown_voltage_) {
      const double knee = *breakdown_voltage_;
      fraction = std::min(fraction, junction_step_fraction(-(v + knee), -(v_next + knee), breakdown_thermal_voltage_,
                                                           critical_breakdown_voltage_));
    }
    return fraction;
  }

  void edges(std::vector<Edge>& out) const override {
    out.push_back({junction_, cathode_, Connection::conductive, name()});
    if (series_resistance_ > 0) out.push_back({anode_, junction_, Connection::conductive, name()});
  }

  // Energy in the junction charge: the integral of v dq from 0 to v (composite Simpson on
  // v C(v); only evaluated at events, for the jump energy balance).
  double stored_energy(const Vector& x) const override {
    if (junction_capacitance_ == 0 && transit_time_ == 0) return 0;
    const double v = junction_voltage(x);
    constexpr int intervals = 256;
    const double h = v / intervals;
    auto integrand = [&](double u) {
      return u * (junction_charge(u).second + transit_time_ * junction_current(u).second);
    };
    double sum = integrand(0) + integrand(v);
    for (int k = 1; k < intervals; ++k) sum += (k % 2 ? 4 : 2) * integrand(k * h);
    return sum * h / 3;
  }

  // Junction current without GMIN and its derivative (ngspice dioload.c: forward exponential,
  // reverse cubic above -3 N Vt, breakdown exponential beyond the knee).
  std::pair<double, double> junction_current(double v) const {
    const double is = saturation_current_, vt = thermal_voltage_;
    if (v >= -3 * vt) {
      const auto [ex, dex] = limited_exp(v / vt);
      return {is * (ex - 1), is * dex / vt};
    }
    if (!breakdown_voltage_ || v >= -*breakdown_voltage_) {
      double a = 3 * vt / (v * std::numbers::e);
      a = a * a * a;
      return {-is * (1 + a), is * 3 * a / v};
    }
    const double vtb = breakdown_thermal_voltage_;
    const auto [ex, dex] = limited_exp(-(*breakdown_voltage_ + v) / vtb);
    return {-is * ex, is * dex / vtb};
  }

  // Depletion charge and capacitance (SPICE: power law below FC VJ, linear extrapolation of the
  // capacitance above).
  std::pair<double, double> junction_charge(double v) const {
    const double cj = junction_capacitance_, vj = junction_potential_, m = grading_, fc = depletion_fraction_;
    if (cj == 0) return {0, 0};
    if (v < fc * vj) {
      const double arg = 1 - v / vj, sarg = std::exp(-m * std::log(arg));
      return {vj * cj * (1 - arg * sarg) / (1 - m), cj * sarg};
    }
    const double f1 = vj * (1 - std::pow(1 - fc, 1 - m)) / (1 - m);
    const double f2 = std::pow(1 - fc, 1 + m), f3 = 1 - fc * (1 + m);
    const double q = cj * f1 + cj / f2 * (f3 * (v - fc * vj) + m / (2 * vj) * (v * v - fc * vj * fc * vj));
    return {q, cj / f2 * (f3 + m * v / vj)};
  }

 private:
  double junction_voltage(const Vector& x) const { return value(x, junction_) - value(x, cathode_); }

  // pnjlim's critical voltage, where the current-voltage curve bends most sharply (its radius
  // of curvature is least). At least vt, so that the limit below stays a forward voltage for
  // any IS.
  double critical_voltage(double vt) const {
    return std::max(vt, vt * std::log(vt / (std::numbers::sqrt2 * saturation_current_)));
  }

  // The fraction of a step from v to v_next along an exponential exp(v / vt) that pnjlim (in its
  // Berkeley form) lets through: a step more than 2 vt forward that ends past the critical
  // voltage stops where the current has grown by the factor the linearization at v promised,
  // vt ln(v_next / vt) from reverse bias and v + vt ln(1 + (v_next - v) / vt) from forward bias.
  static double junction_step_fraction(double v, double v_next, double vt, double v_critical) {
    if (!(v_next > v_critical && v_next - v > 2 * vt)) return 1;
    const double limited = v > 0 ? v + vt * std::log1p((v_next - v) / vt) : vt * std::log(v_next / vt);
    return (limited - v) / (v_next - v);
  }

  // exp(x) and its slope, continued linearly above the exponent limit.
  std::pair<double, double> limited_exp(double x) const {
    if (x <= exponent_limit_) {
      const double e = std::exp(x);
      return {e, e};
    }
    const double e = std::exp(exponent_limit_);
    return {e * (1 + x - exponent_limit_), e};
  }

  // ngspice's knee (diotemp.c): the voltage where the breakdown current equals IBV, iterated
  // to RELTOL as there (vt: the thermal voltage without N, as there).
  double breakdown_knee(double bv, double ibv, double vt, double reltol) const {
    const double is = saturation_current_, vtb = breakdown_thermal_voltage_;
    if (ibv < is * bv / vt) return bv;
    double knee = bv - vtb * std::log(1 + ibv / is);
    for (int k = 0; k < 25; ++k) {
      knee = bv - vtb * std::log(ibv / is + 1 - knee / vt);
      const double current = is * (std::exp((bv - knee) / vtb) - 1 + knee / vt);
      if (std::abs(current - ibv) <= reltol * ibv) break;
    }
    return knee;
  }

  double saturation_current_, thermal_voltage_, breakdown_thermal_voltage_, series_resistance_, junction_capacitance_;
  double junction_potential_, grading_, depletion_fraction_, transit_time_;
  double exponent_limit_, critical_voltage_, critical_breakdown_voltage_;
  std::optional<double> breakdown_voltage_;
  int anode_ = ground, cathode_ = ground, junction_ = ground;
  Stamper::Block junction_slots_, series_slots_;
};

const Registration registration("d", [](const ElementSpec& spec, const RunSettings& run, DeviceArena& arena) {
  return arena.make<Diode>(spec, run);
});

}  // namespace
}  // namespace mna
