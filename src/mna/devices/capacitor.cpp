// C between nodes a and b, q = C (va - vb), as a ChargeBranch: a floating capacitor carries its
// current as an unknown of its own.
#include "mna/device.hpp"
#include "mna/devices/charge_branch.hpp"

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
    charge_.allocate(u, a_, b_, name(), name());
  }
  void declare(Stamper& s) override { charge_.declare(s); }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override { charge_.load(e, capacitance_ * (e.value(a_) - e.value(b_)), capacitance_); }
  void edges(std::vector<Edge>& out) const override { out.push_back({a_, b_, Connection::capacitive, name()}); }
  double stored_energy(const Vector& x) const override {
    const double v = value(x, a_) - value(x, b_);
    return 0.5 * capacitance_ * v * v;
  }
  // IC= sets the voltage across: the non-ground node (or node a, relative to node b).
  std::optional<InitialConditionAt> initial_condition_at(const Vector& x) const override {
    if (!card().initial_condition) return std::nullopt;
    return InitialConditionAt{*card().initial_condition, value(x, a_) - value(x, b_), a_ != ground ? a_ : b_};
  }
  std::optional<InitialVoltage> initial_voltage() const override {
    if (!card().initial_condition) return std::nullopt;
    return InitialVoltage{a_, b_, *card().initial_condition};
  }

 private:
  double capacitance_;
  int a_ = ground, b_ = ground;
  ChargeBranch charge_;
};

const Registration registration("c", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Capacitor>(spec);
});

}  // namespace
}  // namespace mna
