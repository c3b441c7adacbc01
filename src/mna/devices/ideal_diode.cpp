// Ideal diode (.model D with IDEAL=1): a predicate with its on/off mode held in an auxiliary
// unknown. Its characteristic is two lines meeting at the knee (VFWD, I_knee = VFWD / ROFF):
// off, i = v / ROFF up to the knee; on, the line of slope 1 / RON through the knee. Off -> on
// when the voltage exceeds VFWD, on -> off when the current falls below I_knee:
//     guard = mode ? i - I_knee : (va - vk - VFWD)
// Branch current i from anode to cathode; row: on: (va - vk - VFWD) / RON - (i - I_knee) = 0, or
// va - vk - VFWD = 0 for RON = 0 (the default); off: i = 0 for ROFF infinite (the default), or
// (va - vk) / ROFF - i = 0.
// Continuous, because a gap between the lines (the on line through (VFWD, 0)) has no mode
// consistent where the circuit drives a current inside it: a bridge's diode whose line
// inductor carried the other diodes' leakage there toggled every 0.6 ns for a microsecond.
#include <cmath>

#include "mna/device.hpp"

namespace mna {
namespace {

class IdealDiode final : public PredicateDevice {
 public:
  explicit IdealDiode(const ElementSpec& spec)
      : PredicateDevice(spec), on_resistance_(parameter(spec, "ron", 0)),
        off_resistance_(parameter(spec, "roff", infinity)), forward_voltage_(parameter(spec, "vfwd", 0)) {
    require_nodes(spec, 2);
    if (!(on_resistance_ >= 0) || !std::isfinite(on_resistance_) || !(off_resistance_ > on_resistance_))
      throw ModelError("diode '" + spec.name + "': need 0 <= RON < ROFF, RON finite");
  }
  void allocate(Unknowns& u) override {
    a_ = u.node(card().nodes[0]), k_ = u.node(card().nodes[1]);
    branch_ = u.add("i(" + name() + ")", UnknownCategory::branch_current, name());
    mode_ = u.add("mode(" + name() + ")", UnknownCategory::auxiliary, name());
  }
  void declare(Stamper& s) override {
    s.entry(a_, branch_, slot_a_branch_), s.entry(k_, branch_, slot_k_branch_);
    s.entry(branch_, a_, slot_branch_a_), s.entry(branch_, k_, slot_branch_k_);
    s.entry(branch_, branch_, slot_branch_branch_);
  }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const bool on = e.p[first_predicate()];
    const double v = e.value(a_) - e.value(k_), i = e.value(branch_);
    e.f(a_, i), e.f(k_, -i);
    const double r = on ? on_resistance_ : off_resistance_, offset = on ? forward_voltage_ : 0;
    const double alpha = r == 0 ? 1 : 1 / r, beta = r == 0 ? 0 : 1;
    e.f(branch_, alpha * (v - offset) - beta * (i - (on ? knee_current() : 0)));
    if (!e.jacobian()) return;
    e.df(slot_a_branch_, 1), e.df(slot_k_branch_, -1);
    e.df(slot_branch_a_, alpha), e.df(slot_branch_k_, -alpha), e.df(slot_branch_branch_, -beta);
  }
  void edges(std::vector<Edge>& out) const override { out.push_back({a_, k_, Connection::conductive, name()}); }
  void mode_edges(const padae::Predicates& p, std::vector<Edge>& out) const override {
    const double r = p[first_predicate()] ? on_resistance_ : off_resistance_;
    if (r == 0) out.push_back({a_, k_, Connection::voltage_defined, name()});
    else if (!std::isinf(r)) out.push_back({a_, k_, Connection::conductive, name()});
  }

  int predicate_count() const override { return 1; }
  std::string predicate_label(int) const override { return "conducting"; }
  void guards(double, const Vector& x, double* out) const override {
    const bool mode = x[mode_] > 0.5;
    out[0] = mode ? x[branch_] - knee_current() : value(x, a_) - value(x, k_) - forward_voltage_;
  }
  void jump_entries(std::vector<padae::JumpEntry>& out) const override {
    out.push_back({mode_, first_predicate(), 1.0});
  }

 private:
  double knee_current() const { return forward_voltage_ / off_resistance_; }
  double on_resistance_, off_resistance_, forward_voltage_;
  int a_ = ground, k_ = ground, branch_ = ground, mode_ = ground;
  int slot_a_branch_ = -1, slot_k_branch_ = -1, slot_branch_a_ = -1, slot_branch_k_ = -1, slot_branch_branch_ = -1;
};

const Registration registration("d:ideal", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<IdealDiode>(spec);
});

}  // namespace
}  // namespace mna
