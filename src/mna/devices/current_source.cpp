// I: current I(t) from node a through the source to node b.
#include "mna/device.hpp"
#include "mna/waveform.hpp"

namespace mna {
namespace {

class CurrentSource final : public Device {
 public:
  CurrentSource(const ElementSpec& spec, const RunSettings& run)
      : Device(spec), function_(spec.waveform, spec.value, run, spec.name) {
    require_nodes(spec, 2);
  }
  void allocate(Unknowns& u) override { a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]); }
  void declare(Stamper&) override {}
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const double i = function_.value(e.t);
    e.f(a_, i), e.f(b_, -i);
  }
  void edges(std::vector<Edge>& out) const override { out.push_back({a_, b_, Connection::current_defined, name()}); }
  bool time_dependent() const override { return true; }
  double next_time_event(double t) const override { return function_.next_corner(t); }
  void forcing_rows(std::vector<int>& out) const override {
    for (int node : {a_, b_})
      if (node != ground) out.push_back(node);
  }
  double resolution_step() const override { return function_.resolution_step(); }
  bool jumps_at(double t) const override { return function_.jumps_at(t); }

 private:
  SourceFunction function_;
  int a_ = ground, b_ = ground;
};

const Registration registration("i", [](const ElementSpec& spec, const RunSettings& run, DeviceArena& arena) {
  return arena.make<CurrentSource>(spec, run);
});

}  // namespace
}  // namespace mna
