// D: the junction diode with ngspice's equations (level 1: IS, N, RS, CJO, VJ, M, FC, TT, BV,
// IBV, NBV, area), for regression against ngspice. The junction current, its charge and GMIN in
// parallel are loaded at the junction voltage; RS adds an internal node. The charge is a
// ChargeBranch: a junction between two nodes off ground carries its current as an unknown.
// Newton's steps into forward conduction (and into breakdown) are limited as ngspice's pnjlim
// limits them. Past the limit a step may still land at huge forward voltages (modified Newton on
// a held matrix): where the junction current would pass 1 kA (or at 40 thermal voltages,
// whichever comes first) the exponential continues linearly, value and slope matching, so f
// stays smooth and finite; solutions below that current are the same.
#include <cmath>
#include <numbers>
#include <optional>

#include "mna/device.hpp"
#include "mna/devices/charge_branch.hpp"
#include "mna/devices/junction.hpp"

namespace mna {
namespace {

using junction::gmin;

class Diode final : public Device {
 public:
  Diode(const ElementSpec& spec, const RunSettings& run) : Device(spec) {
    require_nodes(spec, 2);
    const double area = spec.area, vt = junction::nominal_thermal_voltage;
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
    exponent_limit_ = junction::exponent_limit(saturation_current_ / area);
    critical_voltage_ = junction::critical_voltage(thermal_voltage_, saturation_current_);
    critical_breakdown_voltage_ = junction::critical_voltage(breakdown_thermal_voltage_, saturation_current_);
    if (!(exponent_limit_ > 1)) throw ModelError("diode '" + spec.name + "': IS too large");
    if (auto bv = spec.model.find("bv"); bv != spec.model.end() && std::isfinite(bv->second))
      // IBV is not scaled by the area (ngspice's level 1, diotemp.c), though IS is.
      breakdown_voltage_ = breakdown_knee(bv->second, parameter(spec, "ibv", 1e-3), vt, run.reltol);
  }

  void allocate(Unknowns& u) override {
    anode_ = u.node(card().nodes[0]), cathode_ = u.node(card().nodes[1]);
    junction_ = anode_;
    if (series_resistance_ > 0)
      junction_ = u.add("v(" + name() + "#internal)", UnknownCategory::internal_node, name());
    if (charged()) charge_.allocate(u, junction_, cathode_, name() + "#junction", name());
  }
  void declare(Stamper& s) override {
    s.block(junction_, cathode_, junction_slots_);
    if (charged()) charge_.declare(s);
    if (series_resistance_ > 0) s.block(anode_, junction_, series_slots_);
  }
  void load(Evaluation& e) const override {
    const double v = e.value(junction_) - e.value(cathode_);
    const auto [current, conductance] = junction_current(v);
    const double i = current + gmin * v;
    e.f(junction_, i), e.f(cathode_, -i);
    if (charged()) {
      const auto [q, c] = junction_charge(v);
      charge_.load(e, q + transit_time_ * current, c + transit_time_ * conductance);
    }
    if (series_resistance_ > 0) {
      const double g = 1 / series_resistance_, ir = g * (e.value(anode_) - e.value(junction_));
      e.f(anode_, ir), e.f(junction_, -ir);
      if (e.jacobian()) e.df(series_slots_, g);
    }
    if (!e.jacobian()) return;
    e.df(junction_slots_, conductance + gmin);
  }
  int kink_count() const override { return 1; }
  void kinks(const Vector& x, double* out) const override { out[0] = junction_voltage(x); }
  bool limits_newton_steps() const override { return true; }
  double newton_step_fraction(const Vector& x, const Vector& x_next) const override {
    const double v = junction_voltage(x), v_next = junction_voltage(x_next);
    double fraction = junction::step_fraction(v, v_next, thermal_voltage_, critical_voltage_);
    if (breakdown_voltage_) {
      const double knee = *breakdown_voltage_;
      fraction = std::min(fraction, junction::step_fraction(-(v + knee), -(v_next + knee), breakdown_thermal_voltage_,
                                                           critical_breakdown_voltage_));
    }
    return fraction;
  }

  bool currents_converged(const Vector& x_before, const Vector& x_after, double rtol, double abstol) const override {
    return junction::current_converged([this](double v) { return junction_current(v); }, junction_voltage(x_before),
                                       junction_voltage(x_after), rtol, abstol);
  }

  void edges(std::vector<Edge>& out) const override {
    out.push_back({junction_, cathode_, Connection::conductive, name()});
    if (series_resistance_ > 0) out.push_back({anode_, junction_, Connection::conductive, name()});
  }

  double stored_energy(const Vector& x) const override {
    if (!charged()) return 0;
    return junction::charge_energy(junction_voltage(x), [&](double u) {
      return junction_charge(u).second + transit_time_ * junction_current(u).second;
    });
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

  std::pair<double, double> junction_charge(double v) const {
    return junction::depletion_charge(v, junction_capacitance_, junction_potential_, grading_, depletion_fraction_);
  }

 private:
  bool charged() const { return junction_capacitance_ > 0 || transit_time_ > 0; }
  double junction_voltage(const Vector& x) const { return value(x, junction_) - value(x, cathode_); }

  std::pair<double, double> limited_exp(double x) const { return junction::limited_exp(x, exponent_limit_); }

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
  ChargeBranch charge_;
};

const Registration registration("d", [](const ElementSpec& spec, const RunSettings& run, DeviceArena& arena) {
  return arena.make<Diode>(spec, run);
});

}  // namespace
}  // namespace mna
