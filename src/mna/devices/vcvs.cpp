// E: va - vb = gain (vc - vd), with a branch current like a voltage source.
#include "mna/device.hpp"

namespace mna {
namespace {

class Vcvs final : public Device {
 public:
  explicit Vcvs(const ElementSpec& spec) : Device(spec), gain_(spec.value) {
    require_nodes(spec, 4);
  }
  void allocate(Unknowns& u) override {
    for (int k = 0; k < 4; ++k) n_[k] = u.node(card().nodes[k]);
    branch_ = u.add("i(" + name() + ")", UnknownCategory::branch_current, name());
  }
  void declare(Stamper& s) override {
    s.entry(n_[0], branch_, slot_a_branch_), s.entry(n_[1], branch_, slot_b_branch_);
    for (int k = 0; k < 4; ++k) s.entry(branch_, n_[k], slot_row_[k]);
  }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const double i = e.value(branch_);
    e.f(n_[0], i), e.f(n_[1], -i);
    e.f(branch_, e.value(n_[0]) - e.value(n_[1]) - gain_ * (e.value(n_[2]) - e.value(n_[3])));
    if (!e.jacobian()) return;
    e.df(slot_a_branch_, 1), e.df(slot_b_branch_, -1);
    e.df(slot_row_[0], 1), e.df(slot_row_[1], -1), e.df(slot_row_[2], -gain_), e.df(slot_row_[3], gain_);
  }
  void edges(std::vector<Edge>& out) const override {
    out.push_back({n_[0], n_[1], Connection::voltage_defined, name()});
  }

 private:
  double gain_;
  int n_[4] = {ground, ground, ground, ground};
  int branch_ = ground;
  int slot_a_branch_ = -1, slot_b_branch_ = -1, slot_row_[4] = {-1, -1, -1, -1};
};

const Registration registration("e", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Vcvs>(spec);
});

}  // namespace
}  // namespace mna
