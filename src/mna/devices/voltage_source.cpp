// V: branch current i from node a through the source to node b; va - vb = V(t).
#include "mna/device.hpp"
#include "mna/waveform.hpp"

namespace mna {
namespace {

class VoltageSource final : public Device {
 public:
  VoltageSource(const ElementSpec& spec, const RunSettings& run)
      : Device(spec), function_(spec.waveform, spec.value, run, spec.name) {
    require_nodes(spec, 2);
  }
  void allocate(Unknowns& u) override {
    a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]);
    branch_ = u.add("i(" + name() + ")", UnknownCategory::branch_current, name());
  }
  void declare(Stamper& s) override {
    s.entry(a_, branch_, slot_a_branch_), s.entry(b_, branch_, slot_b_branch_);
    s.entry(branch_, a_, slot_branch_a_), s.entry(branch_, b_, slot_branch_b_);
  }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const double i = e.value(branch_);
    e.f(a_, i), e.f(b_, -i);
    e.f(branch_, e.value(a_) - e.value(b_) - function_.value(e.t));
    if (!e.jacobian()) return;
    e.df(slot_a_branch_, 1), e.df(slot_b_branch_, -1);
    e.df(slot_branch_a_, 1), e.df(slot_branch_b_, -1);
  }
  void edges(std::vector<Edge>& out) const override { out.push_back({a_, b_, Connection::voltage_defined, name()}); }
  bool time_dependent() const override { return true; }
  double next_time_event(double t) const override { return function_.next_corner(t); }
  void forcing_rows(std::vector<int>& out) const override { out.push_back(branch_); }
  double resolution_step() const override { return function_.resolution_step(); }
  bool jumps_at(double t) const override { return function_.jumps_at(t); }
  // The branch current enters node a's side of the source: the source delivers -V i.
  double delivered_energy(double t, const Vector& impulse) const override {
    return -function_.value(t) * impulse[branch_];
  }

 private:
  SourceFunction function_;
  int a_ = ground, b_ = ground, branch_ = ground;
  int slot_a_branch_ = -1, slot_b_branch_ = -1, slot_branch_a_ = -1, slot_branch_b_ = -1;
};

const Registration registration("v", [](const ElementSpec& spec, const RunSettings& run, DeviceArena& arena) {
  return arena.make<VoltageSource>(spec, run);
});

}  // namespace
}  // namespace mna
