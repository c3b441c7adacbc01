// R: i = (va - vb) / R, leaving node a.
#include "mna/device.hpp"

namespace mna {
namespace {

class Resistor final : public Device {
 public:
  explicit Resistor(const ElementSpec& spec) : Device(spec), conductance_(1 / spec.value) {
    require_nodes(spec, 2);
    if (!(spec.value != 0) || !std::isfinite(spec.value))
      throw ModelError("resistor '" + spec.name + "': resistance must be finite and non-zero");
  }
  void allocate(Unknowns& u) override { a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]); }
  void declare(Stamper& s) override { s.block(a_, b_, slots_); }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const double i = conductance_ * (e.value(a_) - e.value(b_));
    e.f(a_, i), e.f(b_, -i);
    if (e.jacobian()) e.df(slots_, conductance_);
  }
  void edges(std::vector<Edge>& out) const override { out.push_back({a_, b_, Connection::conductive, name()}); }

 private:
  double conductance_;
  int a_ = ground, b_ = ground;
  Stamper::Block slots_;
};

const Registration registration("r", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Resistor>(spec);
});

}  // namespace
}  // namespace mna
