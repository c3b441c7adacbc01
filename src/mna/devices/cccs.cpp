// F: current gain * i(control) from node a through the source to node b.
#include "mna/device.hpp"

namespace mna {
namespace {

class Cccs final : public Device {
 public:
  explicit Cccs(const ElementSpec& spec) : Device(spec), gain_(spec.value) {
    require_nodes(spec, 2);
    if (spec.controls.size() != 1) throw ModelError("element '" + spec.name + "' needs one controlling source");
  }
  void allocate(Unknowns& u) override { a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]); }
  void declare(Stamper& s) override {
    control_ = s.unknowns().branch(card().controls[0]);
    s.entry(a_, control_, slot_a_), s.entry(b_, control_, slot_b_);
  }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const double i = gain_ * e.value(control_);
    e.f(a_, i), e.f(b_, -i);
    if (e.jacobian()) e.df(slot_a_, gain_), e.df(slot_b_, -gain_);
  }
  void edges(std::vector<Edge>& out) const override { out.push_back({a_, b_, Connection::current_defined, name()}); }

 private:
  double gain_;
  int a_ = ground, b_ = ground, control_ = ground, slot_a_ = -1, slot_b_ = -1;
};

const Registration registration("f", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Cccs>(spec);
});

}  // namespace
}  // namespace mna
