#include "mna/devices/inductor.hpp"

namespace mna {

Inductor::Inductor(const ElementSpec& spec)
    : Device(spec), inductance_(spec.value) {
  require_nodes(spec, 2);
  if (!(spec.value > 0) || !std::isfinite(spec.value))
    throw ModelError("inductor '" + spec.name + "': inductance must be positive and finite");
}

void Inductor::allocate(Unknowns& u) {
  a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]);
  branch_ = u.add("i(" + name() + ")", UnknownCategory::branch_current, name());
}

void Inductor::declare(Stamper& s) {
  s.entry(a_, branch_, slot_a_branch_), s.entry(b_, branch_, slot_b_branch_);
  s.entry(branch_, a_, slot_branch_a_), s.entry(branch_, b_, slot_branch_b_);
  s.charge_entry(branch_, branch_, slot_flux_);
}

void Inductor::load(Evaluation& e) const {
  const double i = e.value(branch_);
  e.f(a_, i), e.f(b_, -i);
  e.f(branch_, e.value(a_) - e.value(b_));
  e.q(branch_, -inductance_ * i);
  if (!e.jacobian()) return;
  e.df(slot_a_branch_, 1), e.df(slot_b_branch_, -1);
  e.df(slot_branch_a_, 1), e.df(slot_branch_b_, -1);
  e.dq(slot_flux_, -inductance_);
}

void Inductor::edges(std::vector<Edge>& out) const { out.push_back({a_, b_, Connection::inductive, name()}); }

double Inductor::stored_energy(const Vector& x) const { return 0.5 * inductance_ * x[branch_] * x[branch_]; }

void Inductor::initial_condition(Vector& x0) const {
  if (card().initial_condition) x0[branch_] = *card().initial_condition;
}

std::optional<Device::InitialConditionAt> Inductor::initial_condition_at(const Vector& x) const {
  if (!card().initial_condition) return std::nullopt;
  return InitialConditionAt{*card().initial_condition, x[branch_], branch_};
}

namespace {
const Registration registration("l", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<Inductor>(spec);
});
}  // namespace

}  // namespace mna
