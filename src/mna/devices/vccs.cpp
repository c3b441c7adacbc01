// G: current gain (vc - vd) from node a through the source to node b.
#include "mna/device.hpp"

namespace mna {
namespace {

class Vccs final : public Device {
 public:
  explicit Vccs(const ElementSpec& spec) : Device(spec), gain_(spec.value) {
    require_nodes(spec, 4);
  }
  void allocate(Unknowns& u) override {
    for (int k = 0; k < 4; ++k) n_[k] = u.node(card().nodes[k]);
  }
  void declare(Stamper& s) override {
    s.entry(n_[0], n_[2], slots_[0]), s.entry(n_[0], n_[3], slots_[1]);
    s.entry(n_[1], n_[2], slots_[2]), s.entry(n_[1], n_[3], slots_[3]);
  }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const double i = gain_ * (e.value(n_[2]) - e.value(n_[3]));
    e.f(n_[0], i), e.f(n_[1], -i);
    if (e.jacobian()) e.df(slots_[0], gain_), e.df(slots_[1], -gain_), e.df(slots_[2], -gain_), e.df(slots_[3], gain_);
  }
  void edges(std::vector<Edge>& out) const override {
    const std::vector<int> read = gain_ != 0 ? std::vector<int>{n_[2], n_[3]} : std::vector<int>{};
    out.push_back({n_[0], n_[1], current_source_connection(n_[0], n_[1], read), name()});
  }

 private:
  double gain_;
  int n_[4] = {ground, ground, ground, ground};
  int slots_[4] = {-1, -1, -1, -1};
};

const Registration registration("g", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Vccs>(spec);
});

}  // namespace
}  // namespace mna
