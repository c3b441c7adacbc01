// L, visible to K (mutual coupling), which adds to its flux row.
#pragma once

#include "mna/device.hpp"

namespace mna {

// Branch current i from node a through the inductor to node b. Branch row in flux form:
// d/dt(-L i) + (va - vb) = 0.
class Inductor final : public Device {
 public:
  explicit Inductor(const ElementSpec& spec);
  void allocate(Unknowns& u) override;
  void declare(Stamper& s) override;
  bool constant_jacobian() const override { return true; }
  void load(Evaluation& e) const override;
  void edges(std::vector<Edge>& out) const override;
  double stored_energy(const Vector& x) const override;
  void initial_condition(Vector& x0) const override;
  std::optional<InitialConditionAt> initial_condition_at(const Vector& x) const override;

  double inductance() const { return inductance_; }
  int branch() const { return branch_; }

 private:
  double inductance_;
  int a_ = ground, b_ = ground, branch_ = ground;
  int slot_a_branch_ = -1, slot_b_branch_ = -1, slot_branch_a_ = -1, slot_branch_b_ = -1;
  int slot_flux_ = -1;
};

}  // namespace mna
