// K: mutual inductance M = k sqrt(L1 L2) adds -M i2 to the flux row of L1 and -M i1 to L2's.
#include <cmath>

#include "mna/devices/inductor.hpp"

namespace mna {
namespace {

class MutualInductance final : public Device {
 public:
  explicit MutualInductance(const ElementSpec& spec) : Device(spec), coupling_(spec.value) {
    if (spec.controls.size() != 2) throw ModelError("coupling '" + spec.name + "' needs two inductors");
    if (spec.controls[0] == spec.controls[1])
      throw ModelError("coupling '" + spec.name + "' couples '" + spec.controls[0] + "' with itself: it needs two different inductors");
    if (!(std::abs(coupling_) <= 1)) throw ModelError("coupling '" + spec.name + "': |k| must not exceed 1");
  }
  void declare(Stamper& s) override {
    const Inductor* l1 = inductor(s, card().controls[0]);
    const Inductor* l2 = inductor(s, card().controls[1]);
    mutual_ = coupling_ * std::sqrt(l1->inductance() * l2->inductance());
    branch1_ = l1->branch(), branch2_ = l2->branch();
    s.charge_entry(branch1_, branch2_, slot12_), s.charge_entry(branch2_, branch1_, slot21_);
  }
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override {
    e.q(branch1_, -mutual_ * e.value(branch2_)), e.q(branch2_, -mutual_ * e.value(branch1_));
    if (e.jacobian()) e.dq(slot12_, -mutual_), e.dq(slot21_, -mutual_);
  }
  void edges(std::vector<Edge>&) const override {}
  double stored_energy(const Vector& x) const override { return mutual_ * x[branch1_] * x[branch2_]; }

 private:
  const Inductor* inductor(const Stamper& s, const std::string& element) const {
    auto* found = dynamic_cast<const Inductor*>(s.device(element));
    if (!found) throw ModelError("coupling '" + name() + "': '" + element + "' is not an inductor of the circuit");
    return found;
  }
  double coupling_;
  double mutual_ = 0;
  int branch1_ = ground, branch2_ = ground, slot12_ = -1, slot21_ = -1;
};

const Registration registration("k", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<MutualInductance>(spec);
});

}  // namespace
}  // namespace mna
