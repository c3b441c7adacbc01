// M: the level-1 MOSFET with ngspice's equations (mos1load.c) at the nominal temperature, for
// regression against ngspice: the Shichman-Hodges drain current with body effect (VTO, KP, GAMMA,
// PHI, LAMBDA; W, L, LD, M), drain and source swapping where vds changes sign, the bulk-drain and
// bulk-source junctions (IS or JS with AD and AS; their depletion charges from CBD, CBS or CJ,
// CJSW, PB, MJ, MJSW, FC), the overlap capacitances CGSO, CGDO, CGBO, and RD, RS (or RSH with
// NRD, NRS) as internal nodes. The Meyer gate capacitances that TOX switches on in ngspice are
// not modelled (the netlist layer refuses TOX): ngspice integrates them as capacitances averaged
// over its step, which is no charge.
//
// ngspice works in voltages multiplied by the type sign (+1 NMOS, -1 PMOS) so that one set of
// equations serves both; so does this file ("normalized" below). A current computed there flows,
// in the circuit, type times as written.
//
// The drain current is continuous with its first derivatives across cutoff, saturation and the
// linear region; only the bulk junctions are exponential, and Newton's steps into their forward
// conduction are limited as ngspice's pnjlim limits them.
#include <algorithm>
#include <cmath>

#include "mna/device.hpp"
#include "mna/devices/junction.hpp"

namespace mna {
namespace {

using junction::gmin;

constexpr double default_length = 1e-4;  // ngspice's DEFL and DEFW, 100 um
constexpr double default_width = 1e-4;

class Mosfet final : public Device {
 public:
  explicit Mosfet(const ElementSpec& spec) : Device(spec) {
    require_nodes(spec, 4);
    type_ = spec.value < 0 ? -1 : 1;
    auto instance = [&](const char* name, double fallback) {
      const auto found = spec.instance_parameters.find(name);
      return found == spec.instance_parameters.end() ? fallback : found->second;
    };
    const double length = instance("l", default_length), width = instance("w", default_width);
    const double multiplier = instance("m", 1);
    const double drain_area = instance("ad", 0), source_area = instance("as", 0);
    const double drain_perimeter = instance("pd", 0), source_perimeter = instance("ps", 0);
    const double effective_length = length - 2 * parameter(spec, "ld", 0);
    if (!(width > 0) || !(effective_length > 0) || !(multiplier > 0))
      throw ModelError("MOSFET '" + spec.name + "': W, M and the effective length L - 2 LD must be positive");

    beta_ = parameter(spec, "kp", 2e-5) * multiplier * width / effective_length;
    gamma_ = parameter(spec, "gamma", 0);
    phi_ = parameter(spec, "phi", 0.6);
    lambda_ = parameter(spec, "lambda", 0);
    const double vto = parameter(spec, "vto", parameter(spec, "vt0", 0));
    if (!(phi_ > 0) || !(beta_ > 0) || !(gamma_ >= 0))
      throw ModelError("MOSFET '" + spec.name + "': parameters out of range (KP, PHI > 0, GAMMA >= 0)");
    // ngspice's tVbi: the threshold without the body effect's sqrt(PHI) part.
    built_in_ = vto - type_ * gamma_ * std::sqrt(phi_);

    const double saturation_current = parameter(spec, "is", 1e-14), current_density = parameter(spec, "js", 0);
    if (current_density == 0 || drain_area == 0 || source_area == 0) {
      drain_.saturation = source_.saturation = multiplier * saturation_current;
    } else {
      drain_.saturation = current_density * multiplier * drain_area;
      source_.saturation = current_density * multiplier * source_area;
    }
    junction_potential_ = parameter(spec, "pb", 0.8);
    bottom_grading_ = parameter(spec, "mj", 0.5);
    sidewall_grading_ = parameter(spec, "mjsw", 0.5);
    depletion_fraction_ = parameter(spec, "fc", 0.5);
    if (!(drain_.saturation >= 0) || !(source_.saturation >= 0) || !(junction_potential_ > 0) ||
        !(bottom_grading_ < 1) || !(sidewall_grading_ < 1) || !(depletion_fraction_ < 1))
      throw ModelError("MOSFET '" + spec.name + "': parameters out of range (IS, JS >= 0, PB > 0, MJ, MJSW, FC < 1)");
    // Zero-bias capacitances: CBD (CBS) as given, else CJ times the area; CJSW times the perimeter.
    auto bottom = [&](const char* given, double area) {
      if (spec.model.contains(given)) return parameter(spec, given, 0) * multiplier;
      return parameter(spec, "cj", 0) * area * multiplier;
    };
    drain_.bottom_capacitance = bottom("cbd", drain_area);
    source_.bottom_capacitance = bottom("cbs", source_area);
    drain_.sidewall_capacitance = parameter(spec, "cjsw", 0) * drain_perimeter * multiplier;
    source_.sidewall_capacitance = parameter(spec, "cjsw", 0) * source_perimeter * multiplier;
    for (Junction* j : {&drain_, &source_}) {  // infinite for IS = 0: a junction of gmin alone
      j->critical_voltage = junction::critical_voltage(thermal_voltage_, j->saturation);
      j->exponent_limit = junction::exponent_limit(j->saturation);
    }

    gate_source_capacitance_ = parameter(spec, "cgso", 0) * multiplier * width;
    gate_drain_capacitance_ = parameter(spec, "cgdo", 0) * multiplier * width;
    gate_bulk_capacitance_ = parameter(spec, "cgbo", 0) * multiplier * effective_length;

    // RD (RS) as given, else RSH times the squares NRD (NRS).
    auto series = [&](const char* given, const char* squares) {
      if (spec.model.contains(given)) return parameter(spec, given, 0) / multiplier;
      return parameter(spec, "rsh", 0) * instance(squares, 1) / multiplier;
    };
    drain_resistance_ = series("rd", "nrd");
    source_resistance_ = series("rs", "nrs");
    if (!(drain_resistance_ >= 0) || !(source_resistance_ >= 0) || !(gate_source_capacitance_ >= 0) ||
        !(gate_drain_capacitance_ >= 0) || !(gate_bulk_capacitance_ >= 0))
      throw ModelError("MOSFET '" + spec.name + "': resistances and capacitances must not be negative");
  }

  void allocate(Unknowns& u) override {
    const auto& nodes = card().nodes;
    drain_node_ = u.node(nodes[0]), gate_ = u.node(nodes[1]), source_node_ = u.node(nodes[2]);
    bulk_ = u.node(nodes[3]);
    drain_.node = drain_node_, source_.node = source_node_;
    if (drain_resistance_ > 0) drain_.node = u.add("v(" + name() + "#drain)", UnknownCategory::internal_node, name());
    if (source_resistance_ > 0)
      source_.node = u.add("v(" + name() + "#source)", UnknownCategory::internal_node, name());
  }

  void declare(Stamper& s) override {
    // The channel's rows (internal drain and source) in the columns of gate, drain, source, bulk:
    // which of the two acts as the drain changes with the sign of vds.
    const int rows[2] = {drain_.node, source_.node}, columns[4] = {gate_, drain_.node, source_.node, bulk_};
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 4; ++c) s.entry(rows[r], columns[c], channel_slots_[r][c]);
    for (Junction* j : {&drain_, &source_}) {
      s.block(bulk_, j->node, j->slots);
      if (j->bottom_capacitance > 0 || j->sidewall_capacitance > 0) s.charge_block(bulk_, j->node, j->slots);
    }
    if (gate_source_capacitance_ > 0) s.charge_block(gate_, source_.node, gate_source_slots_);
    if (gate_drain_capacitance_ > 0) s.charge_block(gate_, drain_.node, gate_drain_slots_);
    if (gate_bulk_capacitance_ > 0) s.charge_block(gate_, bulk_, gate_bulk_slots_);
    if (drain_resistance_ > 0) s.block(drain_node_, drain_.node, drain_series_slots_);
    if (source_resistance_ > 0) s.block(source_node_, source_.node, source_series_slots_);
  }

  void load(Evaluation& e) const override {
    const double vb = e.value(bulk_), vd = e.value(drain_.node), vs = e.value(source_.node), vg = e.value(gate_);
    const bool jacobian = e.jacobian();

    for (const Junction* j : {&drain_, &source_}) {
      const double v = type_ * (vb - e.value(j->node));
      const auto [current, conductance] = junction_current(*j, v);
      e.f(bulk_, type_ * current), e.f(j->node, -type_ * current);
      if (jacobian) e.df(j->slots, conductance);
      if (j->bottom_capacitance > 0 || j->sidewall_capacitance > 0) {
        const auto [q, c] = depletion_charge(*j, v);
        e.q(bulk_, type_ * q), e.q(j->node, -type_ * q);
        if (jacobian) e.dq(j->slots, c);
      }
    }

    // The channel, from whichever of the two acts as the drain (the higher, normalized).
    const bool normal = type_ * (vd - vs) >= 0;
    const int from = normal ? 0 : 1;  // row (and column - 1) of the acting drain in channel_slots_
    const double v_source = normal ? vs : vd, v_drain = normal ? vd : vs;
    const Channel channel = drain_current(type_ * (vg - v_source), type_ * (v_drain - v_source),
                                          type_ * (vb - v_source));
    const int acting_drain = normal ? drain_.node : source_.node, acting_source = normal ? source_.node : drain_.node;
    e.f(acting_drain, type_ * channel.current), e.f(acting_source, -type_ * channel.current);
    if (jacobian) {
      // d(current)/d(gate, acting drain, acting source, bulk): the type signs cancel.
      const double by_drain = channel.gds, by_source = -(channel.gm + channel.gds + channel.gmbs);
      const int drain_column = 1 + from, source_column = 2 - from;
      for (int r = 0; r < 2; ++r) {
        const double sign = r == from ? 1 : -1;
        e.df(channel_slots_[r][0], sign * channel.gm);
        e.df(channel_slots_[r][drain_column], sign * by_drain);
        e.df(channel_slots_[r][source_column], sign * by_source);
        e.df(channel_slots_[r][3], sign * channel.gmbs);
      }
    }

    auto linear_capacitor = [&](int a, int b, double capacitance, const Stamper::Block& slots) {
      if (capacitance == 0) return;
      const double q = capacitance * (e.value(a) - e.value(b));
      e.q(a, q), e.q(b, -q);
      if (jacobian) e.dq(slots, capacitance);
    };
    linear_capacitor(gate_, source_.node, gate_source_capacitance_, gate_source_slots_);
    linear_capacitor(gate_, drain_.node, gate_drain_capacitance_, gate_drain_slots_);
    linear_capacitor(gate_, bulk_, gate_bulk_capacitance_, gate_bulk_slots_);

    auto resistor = [&](int a, int b, double resistance, const Stamper::Block& slots) {
      if (resistance == 0) return;
      const double g = 1 / resistance, i = g * (e.value(a) - e.value(b));
      e.f(a, i), e.f(b, -i);
      if (jacobian) e.df(slots, g);
    };
    resistor(drain_node_, drain_.node, drain_resistance_, drain_series_slots_);
    resistor(source_node_, source_.node, source_resistance_, source_series_slots_);
  }

  bool limits_newton_steps() const override { return true; }
  double newton_step_fraction(const Vector& x, const Vector& x_next) const override {
    double fraction = 1;
    for (const Junction* j : {&drain_, &source_}) {
      if (j->saturation == 0) continue;
      const double v = type_ * (value(x, bulk_) - value(x, j->node));
      const double v_next = type_ * (value(x_next, bulk_) - value(x_next, j->node));
      fraction = std::min(fraction, junction::step_fraction(v, v_next, thermal_voltage_, j->critical_voltage));
    }
    return fraction;
  }
  bool currents_converged(const Vector& x_before, const Vector& x_after, double rtol, double abstol) const override {
    for (const Junction* j : {&drain_, &source_}) {
      if (j->saturation == 0) continue;
      const auto current = [&](double v) { return junction_current(*j, v); };
      if (!junction::current_converged(current, type_ * (value(x_before, bulk_) - value(x_before, j->node)),
                                       type_ * (value(x_after, bulk_) - value(x_after, j->node)), rtol, abstol))
        return false;
    }
    return true;
  }

  // The junctions' gmin always conducts; the channel only when on, the gate only through its
  // overlap capacitances.
  void edges(std::vector<Edge>& out) const override {
    out.push_back({bulk_, drain_.node, Connection::conductive, name()});
    out.push_back({bulk_, source_.node, Connection::conductive, name()});
    out.push_back({drain_.node, source_.node, Connection::conductive, name()});
    if (drain_resistance_ > 0) out.push_back({drain_node_, drain_.node, Connection::conductive, name()});
    if (source_resistance_ > 0) out.push_back({source_node_, source_.node, Connection::conductive, name()});
    if (gate_source_capacitance_ > 0) out.push_back({gate_, source_.node, Connection::capacitive, name()});
    if (gate_drain_capacitance_ > 0) out.push_back({gate_, drain_.node, Connection::capacitive, name()});
    if (gate_bulk_capacitance_ > 0) out.push_back({gate_, bulk_, Connection::capacitive, name()});
  }

  double stored_energy(const Vector& x) const override {
    auto linear = [&](int a, int b, double capacitance) {
      const double v = value(x, a) - value(x, b);
      return 0.5 * capacitance * v * v;
    };
    double energy = linear(gate_, source_.node, gate_source_capacitance_) +
                    linear(gate_, drain_.node, gate_drain_capacitance_) + linear(gate_, bulk_, gate_bulk_capacitance_);
    for (const Junction* j : {&drain_, &source_}) {
      if (j->bottom_capacitance == 0 && j->sidewall_capacitance == 0) continue;
      energy += junction::charge_energy(type_ * (value(x, bulk_) - value(x, j->node)),
                                        [&](double u) { return depletion_charge(*j, u).second; });
    }
    return energy;
  }

 private:
  struct Junction {  // bulk to drain, or bulk to source
    int node = ground;  // the internal drain (source) node, the terminal's without RD (RS)
    double saturation = 0, bottom_capacitance = 0, sidewall_capacitance = 0;
    double critical_voltage = 0, exponent_limit = 0;
    Stamper::Block slots;
  };
  struct Channel {
    double current, gm, gds, gmbs;
  };

  // Normalized junction current from bulk to drain (source) with gmin, and its conductance
  // (mos1load.c: exponential above -3 vt, constant below).
  std::pair<double, double> junction_current(const Junction& j, double v) const {
    if (v <= -3 * thermal_voltage_) return {gmin * v - j.saturation, gmin};
    const auto [ex, dex] = junction::limited_exp(v / thermal_voltage_, j.exponent_limit);
    return {j.saturation * (ex - 1) + gmin * v, j.saturation * dex / thermal_voltage_ + gmin};
  }

  std::pair<double, double> depletion_charge(const Junction& j, double v) const {
    const auto [q_bottom, c_bottom] = junction::depletion_charge(v, j.bottom_capacitance, junction_potential_,
                                                                 bottom_grading_, depletion_fraction_);
    const auto [q_side, c_side] = junction::depletion_charge(v, j.sidewall_capacitance, junction_potential_,
                                                             sidewall_grading_, depletion_fraction_);
    return {q_bottom + q_side, c_bottom + c_side};
  }

  // Shichman-Hodges in normalized voltages of the acting drain (vds >= 0) and source.
  Channel drain_current(double vgs, double vds, double vbs) const {
    // sqrt(PHI - vbs), continued linearly (down to 0) for a forward-biased bulk, and
    // d threshold / d(-vbs). (ngspice's gmbs divides by the continued root instead: not the
    // derivative of its own current there; only Newton's convergence sees the difference.)
    double root, body;
    if (vbs <= 0) {
      root = std::sqrt(phi_ - vbs);
      body = gamma_ / (root + root);
    } else {
      const double root_phi = std::sqrt(phi_);
      root = root_phi - vbs / (root_phi + root_phi);
      body = root > 0 ? gamma_ / (root_phi + root_phi) : 0;
      root = std::max(0.0, root);
    }
    const double threshold = type_ * built_in_ + gamma_ * root;
    const double overdrive = vgs - threshold;
    if (overdrive <= 0) return {0, 0, 0, 0};
    const double beta = beta_ * (1 + lambda_ * vds);
    if (overdrive <= vds) {  // saturation
      const double gm = beta * overdrive;
      return {beta * overdrive * overdrive * 0.5, gm, lambda_ * beta_ * overdrive * overdrive * 0.5, gm * body};
    }
    const double gm = beta * vds;  // linear region
    return {beta * vds * (overdrive - 0.5 * vds), gm,
            beta * (overdrive - vds) + lambda_ * beta_ * vds * (overdrive - 0.5 * vds), gm * body};
  }

  const double thermal_voltage_ = junction::nominal_thermal_voltage;
  double type_ = 1;
  double beta_, gamma_, phi_, lambda_, built_in_;
  double junction_potential_, bottom_grading_, sidewall_grading_, depletion_fraction_;
  double gate_source_capacitance_, gate_drain_capacitance_, gate_bulk_capacitance_;
  double drain_resistance_, source_resistance_;
  Junction drain_, source_;
  int drain_node_ = ground, gate_ = ground, source_node_ = ground, bulk_ = ground;
  int channel_slots_[2][4] = {};
  Stamper::Block gate_source_slots_, gate_drain_slots_, gate_bulk_slots_, drain_series_slots_, source_series_slots_;
};

const Registration registration("m", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Mosfet>(spec);
});

}  // namespace
}  // namespace mna
