// C: charge q = C (va - vb) on node a, -q on node b.
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
  void allocate(Unknowns& u) override { a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]); }
  void declare(Stamper& s) override { s.charge_block(a_, b_, slots_); }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const double q = capacitance_ * (e.value(a_) - e.value(b_));
    e.q(a_, q), e.q(b_, -q);
    if (e.jacobian()) e.dq(slots_, capacitance_);
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
  Stamper::Block slots_;
};

const Registration registration("c", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Capacitor>(spec);
});

}  // namespace
}  // namespace mna
