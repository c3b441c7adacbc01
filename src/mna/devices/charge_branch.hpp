// A two-terminal charge q(va - vb): a capacitor's, a junction's. With a node at ground it enters
// the other node's row. Between two nodes off ground it carries its current i as an unknown, from
// a through the charge to b: its own row d/dt q - i = 0 holds the charge, the node rows only +-i
// (as an inductor's branch does). In the node rows C/h would swamp whatever else ties the two
// nodes' common mode down: a transformer's secondary on 1 MOhm, its 100 uF output capacitor
// stepped at 1e-16 s after a hard switching edge (C/h = 1e12 S against 1 uS), is singular to
// rounding there, and so are its rectifier diodes' 1 nF junctions at 1e-16 s.
#pragma once

#include <string>

#include "mna/device.hpp"

namespace mna {

class ChargeBranch {
 public:
  // The current is named i(label); no element or probe names it.
  void allocate(Unknowns& u, int a, int b, const std::string& label, const std::string& owner) {
    a_ = a, b_ = b;
    if (a_ != ground && b_ != ground) current_ = u.add("i(" + label + ")", UnknownCategory::internal_current, owner);
  }
  void declare(Stamper& s) {
    if (current_ == ground) return s.charge_block(a_, b_, node_rows_);
    s.entry(a_, current_, slot_a_current_), s.entry(b_, current_, slot_b_current_);
    s.entry(current_, current_, slot_current_);
    s.charge_entry(current_, a_, slot_charge_a_), s.charge_entry(current_, b_, slot_charge_b_);
  }
  // q at the present voltage across, and its capacitance dq/dv there.
  void load(Evaluation& e, double q, double capacitance) const {
    if (current_ == ground) {
      e.q(a_, q), e.q(b_, -q);
      if (e.jacobian()) e.dq(node_rows_, capacitance);
      return;
    }
    const double i = e.value(current_);
    e.f(a_, i), e.f(b_, -i);
    e.q(current_, q), e.f(current_, -i);
    if (!e.jacobian()) return;
    e.df(slot_a_current_, 1), e.df(slot_b_current_, -1), e.df(slot_current_, -1);
    e.dq(slot_charge_a_, capacitance), e.dq(slot_charge_b_, -capacitance);
  }

 private:
  int a_ = ground, b_ = ground;
  int current_ = ground;  // between two nodes off ground only
  Stamper::Block node_rows_;
  int slot_a_current_ = -1, slot_b_current_ = -1, slot_current_ = -1;
  int slot_charge_a_ = -1, slot_charge_b_ = -1;
};

}  // namespace mna
