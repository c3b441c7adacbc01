// H: va - vb = gain * i(control), with a branch current like a voltage source.
#include "mna/device.hpp"

namespace mna {
namespace {

class Ccvs final : public Device {
 public:
  explicit Ccvs(const ElementSpec& spec) : Device(spec), gain_(spec.value) {
    require_nodes(spec, 2);
    if (spec.controls.size() != 1) throw ModelError("element '" + spec.name + "' needs one controlling source");
  }
  void allocate(Unknowns& u) override {
    a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]);
    branch_ = u.add("i(" + name() + ")", UnknownCategory::branch_current, name());
  }
  void declare(Stamper& s) override {
    control_ = s.unknowns().branch(card().controls[0]);
    s.entry(a_, branch_, slot_a_branch_), s.entry(b_, branch_, slot_b_branch_);
    s.entry(branch_, a_, slot_branch_a_), s.entry(branch_, b_, slot_branch_b_);
    s.entry(branch_, control_, slot_branch_control_);
  }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const double i = e.value(branch_);
    e.f(a_, i), e.f(b_, -i);
    e.f(branch_, e.value(a_) - e.value(b_) - gain_ * e.value(control_));
    if (!e.jacobian()) return;
    e.df(slot_a_branch_, 1), e.df(slot_b_branch_, -1);
    e.df(slot_branch_a_, 1), e.df(slot_branch_b_, -1), e.df(slot_branch_control_, -gain_);
  }
  void edges(std::vector<Edge>& out) const override { out.push_back({a_, b_, Connection::voltage_defined, name()}); }

 private:
  double gain_;
  int a_ = ground, b_ = ground, branch_ = ground, control_ = ground;
  int slot_a_branch_ = -1, slot_b_branch_ = -1, slot_branch_a_ = -1, slot_branch_b_ = -1, slot_branch_control_ = -1;
};

const Registration registration("h", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Ccvs>(spec);
});

}  // namespace
}  // namespace mna
