// C between nodes a and b, q = C (va - vb). A grounded capacitor puts q in its node's row. A
// floating one carries its current i as an unknown, from a through the capacitor to b: its own
// row d/dt q - i = 0 holds the charge, the node rows only +-i (as an inductor's branch does).
// In the node rows C/h would swamp whatever else ties the two nodes' common mode down: a
// transformer's secondary on 1 MOhm, its 100 uF output capacitor stepped at 1e-16 s after a
// hard switching edge (C/h = 1e12 S against 1 uS), is singular to rounding there.
#include "mna/device.hpp"

namespace mna {
namespace {

class Capacitor final : public Device {
 public:
  explicit Capacitor(const ElementSpec& spec)
      : Device(spec), capacitance_(spec.value) {
    require_nodes(spec, 2);
    if (!std::isfinite(spec.value))
      throw ModelError("capacitor '" + spec.name + "': capacitance must be finite");
  }
  void allocate(Unknowns& u) override {
    a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]);
    if (a_ != ground && b_ != ground) current_ = u.add("i(" + name() + ")", UnknownCategory::internal_current, name());
  }
  void declare(Stamper& s) override {
    if (current_ == ground) return s.charge_block(a_, b_, charge_slots_);
    s.entry(a_, current_, slot_a_current_), s.entry(b_, current_, slot_b_current_);
    s.entry(current_, current_, slot_current_);
    s.charge_entry(current_, a_, slot_charge_a_), s.charge_entry(current_, b_, slot_charge_b_);
  }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const double q = capacitance_ * (e.value(a_) - e.value(b_));
    if (current_ == ground) {
      e.q(a_, q), e.q(b_, -q);
      if (e.jacobian()) e.dq(charge_slots_, capacitance_);
      return;
    }
    const double i = e.value(current_);
    e.f(a_, i), e.f(b_, -i);
    e.q(current_, q), e.f(current_, -i);
    if (!e.jacobian()) return;
    e.df(slot_a_current_, 1), e.df(slot_b_current_, -1), e.df(slot_current_, -1);
    e.dq(slot_charge_a_, capacitance_), e.dq(slot_charge_b_, -capacitance_);
  }
  void edges(std::vector<Edge>& out) const override { out.push_back({a_, b_, Connection::capacitive, name()}); }
  double stored_energy(const Vector& x) const override {
    const double v = value(x, a_) - value(x, b_);
    return 0.5 * capacitance_ * v * v;
  }
  // IC= sets the voltage across: the non-ground node (or node a, relative to node b).
  void initial_condition(Vector& x0) const override {
    const std::optional<double>& initial_voltage = card().initial_condition;
    if (!initial_voltage) return;
    if (a_ != ground) x0[a_] = value(x0, b_) + *initial_voltage;
    else if (b_ != ground) x0[b_] = -*initial_voltage;
  }

 private:
  double capacitance_;
  int a_ = ground, b_ = ground;
  int current_ = ground;  // floating capacitors only
  Stamper::Block charge_slots_;  // grounded: q in the node rows
  int slot_a_current_ = -1, slot_b_current_ = -1, slot_current_ = -1;
  int slot_charge_a_ = -1, slot_charge_b_ = -1;
};

const Registration registration("c", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Capacitor>(spec);
});

}  // namespace
}  // namespace mna
