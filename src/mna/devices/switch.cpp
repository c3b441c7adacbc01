// S (voltage-controlled) and W (current-controlled) switches with ngspice's semantics: on above
// VT + VH, off below VT - VH, in between, and at either threshold, the state is kept. The state
// is an auxiliary unknown (a mode that only events change); one predicate says "on" with a guard
// on the control, positive where the switch is on:
//     guard = state ? c - below(VT - VH) : c - (VT + VH)
// below(x) the double just below x, so that a control resting at VT - VH keeps the switch on.
// RON = 0 or ROFF = infinite make the switch ideal (IDEAL=1 makes them the defaults, since a
// netlist cannot write infinity); then it carries a branch current i and its
// row reads alpha(p) (va - vb) - beta(p) i = 0 with (alpha, beta) = (1/R, 1), or (1, 0) for
// R = 0, or (0, 1) for R = inf (conductance scaling keeps a large finite R well conditioned).
#include <cmath>

#include "mna/device.hpp"

namespace mna {
namespace {

class Switch final : public PredicateDevice {
 public:
  Switch(const ElementSpec& spec, bool current_controlled)
      : PredicateDevice(spec), current_controlled_(current_controlled),
        threshold_(parameter(spec, current_controlled ? "it" : "vt", 0)),
        hysteresis_(parameter(spec, current_controlled ? "ih" : "vh", 0)),
        on_resistance_(parameter(spec, "ron", parameter(spec, "ideal", 0) != 0 ? 0 : 1)),
        off_resistance_(parameter(spec, "roff", parameter(spec, "ideal", 0) != 0 ? infinity : 1e12)),
        initially_on_(spec.initially_on.value_or(false)) {
    require_nodes(spec, current_controlled ? 2 : 4);
    if (current_controlled && spec.controls.size() != 1)
      throw ModelError("switch '" + spec.name + "' needs one controlling source");
    if (hysteresis_ < 0) throw ModelError("switch '" + spec.name + "': negative hysteresis is not supported");
    if (!(on_resistance_ >= 0) || !(off_resistance_ > on_resistance_) || !std::isfinite(on_resistance_))
      throw ModelError("switch '" + spec.name + "': need 0 <= RON < ROFF, RON finite");
    ideal_ = on_resistance_ == 0 || std::isinf(off_resistance_);
    off_below_ = std::nextafter(threshold_ - hysteresis_, -infinity);
  }

  void allocate(Unknowns& u) override {
    a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]);
    if (!current_controlled_) c_ = u.node(card().nodes[2]), d_ = u.node(card().nodes[3]);
    if (ideal_) branch_ = u.add("i(" + name() + ")", UnknownCategory::branch_current, name());
    state_ = u.add("state(" + name() + ")", UnknownCategory::auxiliary, name());
  }
  void declare(Stamper& s) override {
    if (current_controlled_) c_ = s.unknowns().branch(card().controls[0]);
    if (!ideal_) {
      s.block(a_, b_, slots_);
      return;
    }
    s.entry(a_, branch_, slot_a_branch_), s.entry(b_, branch_, slot_b_branch_);
    s.entry(branch_, a_, slot_branch_a_), s.entry(branch_, b_, slot_branch_b_);
    s.entry(branch_, branch_, slot_branch_branch_);
  }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    const bool on = e.p[first_predicate()];
    const double v = e.value(a_) - e.value(b_);
    if (!ideal_) {
      const double g = on ? 1 / on_resistance_ : 1 / off_resistance_;
      e.f(a_, g * v), e.f(b_, -g * v);
      if (e.jacobian()) e.df(slots_, g);
      return;
    }
    const double r = on ? on_resistance_ : off_resistance_;
    const double alpha = r == 0 ? 1 : 1 / r, beta = r == 0 ? 0 : 1;
    const double i = e.value(branch_);
    e.f(a_, i), e.f(b_, -i);
    e.f(branch_, alpha * v - beta * i);
    if (!e.jacobian()) return;
    e.df(slot_a_branch_, 1), e.df(slot_b_branch_, -1);
    e.df(slot_branch_a_, alpha), e.df(slot_branch_b_, -alpha), e.df(slot_branch_branch_, -beta);
  }
  void edges(std::vector<Edge>& out) const override { out.push_back({a_, b_, Connection::conductive, name()}); }
  void mode_edges(const padae::Predicates& p, std::vector<Edge>& out) const override {
    const double r = p[first_predicate()] ? on_resistance_ : off_resistance_;
    if (r == 0) out.push_back({a_, b_, Connection::voltage_defined, name()});
    else if (!std::isinf(r)) out.push_back({a_, b_, Connection::conductive, name()});
  }

  int predicate_count() const override { return 1; }
  std::string predicate_label(int) const override { return "on"; }
  void guards(double, const Vector& x, double* out) const override {
    const double control = current_controlled_ ? x[c_] : value(x, c_) - value(x, d_);
    const bool state = x[state_] > 0.5;
    out[0] = state ? control - off_below_ : control - (threshold_ + hysteresis_);
  }
  // The state follows the predicate: +1 when it turns on, -1 when it turns off.
  void jump_entries(std::vector<padae::JumpEntry>& out) const override {
    out.push_back({state_, first_predicate(), 1.0});
  }
  void initial_auxiliaries(Vector& x0) const override { x0[state_] = initially_on_ ? 1 : 0; }

 private:
  bool current_controlled_;
  double threshold_, hysteresis_, on_resistance_, off_resistance_;
  double off_below_;  // the largest control that turns the switch off: just below VT - VH
  bool initially_on_;
  bool ideal_ = false;
  int a_ = ground, b_ = ground, c_ = ground, d_ = ground, branch_ = ground, state_ = ground;
  Stamper::Block slots_;
  int slot_a_branch_ = -1, slot_b_branch_ = -1, slot_branch_a_ = -1, slot_branch_b_ = -1, slot_branch_branch_ = -1;
};

const Registration voltage_controlled("s", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Switch>(spec, false);
});
const Registration current_controlled("w", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Switch>(spec, true);
});

}  // namespace
}  // namespace mna
