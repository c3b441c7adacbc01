// A flat circuit as a predicate DAE (padae::System): modified nodal analysis in charge/flux
// form. Unknowns are node voltages (ground excluded), then the branch currents, internal nodes
// and auxiliary mode variables the devices allocate.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "mna/circuit_spec.hpp"
#include "mna/device.hpp"
#include "padae/system.hpp"

namespace mna {

struct Tolerances {
  double voltage = 1e-6;   // node voltages (ngspice's VNTOL)
  double current = 1e-12;  // branch currents (ngspice's ABSTOL)
};

class Model final : public padae::System {
 public:
  // Throws ModelError for an unknown element type, a missing controlling element or a bad
  // parameter.
  Model(CircuitSpec circuit, const RunSettings& settings);

  int size() const override { return unknowns_.size(); }
  padae::UnknownKind kind(int unknown) const override { return kinds_[unknown]; }
  const padae::Pattern& pattern() const override { return pattern_; }
  padae::EvalStatus load(double t, const Vector& x, const padae::Predicates& p, padae::Load& out) override;
  int predicate_count() const override { return predicate_count_; }
  padae::EvalStatus guards(double t, const Vector& x, Vector& out) const override;
  bool has_jumps() const override { return !jump_entries_.empty(); }
  void jump_matrix(double t, const Vector& x, const padae::Predicates& p,
                   std::vector<padae::JumpEntry>& out) const override;
  double next_time_event(double t) const override;
  bool time_event_rows(double t, std::vector<int>& rows) const override;
  double absolute_tolerance(int unknown, double default_atol) const override;
  double newton_step_fraction(const Vector& x, const Vector& x_next) const override;
  bool currents_converged(const Vector& x_before, const Vector& x_after, double rtol) const override;
  int kink_count() const override { return kink_count_; }
  void kinks(const Vector& x, Vector& out) const override;
  // Every device's charges from their values at x (ChargeReference).
  bool measure_charges_from(double t, const Vector& x, const padae::Predicates& p) override;
  // Every device's derivatives depend on the predicates alone. (Holding the .ic voltages changes
  // the held rows' derivatives: it is set for the whole life of a solver, never within one.)
  bool constant_jacobian() const override { return constant_jacobian_; }

  // The longest step that resolves every source's time dependence (a bound for
  // padae::Options::max_step: voltages that merely follow a source are not error-tested).
  double resolution_step() const;
  // Whether a source jumps at t (a time event where the left and right limits differ).
  bool source_jumps_at(double t) const;

  void set_tolerances(const Tolerances& tolerances) { tolerances_ = tolerances; }
  const CircuitSpec& circuit() const { return circuit_; }
  const Unknowns& unknowns() const { return unknowns_; }
  const std::vector<DevicePointer>& devices() const { return devices_; }
  // Node index or ground; -2 when the circuit has no such node.
  int find_node(const std::string& name) const;

  // Who owns predicate k, and what it means ("state", "v(a)>v(b)", ...).
  const Device& predicate_owner(int predicate) const;
  std::string predicate_label(int predicate) const;

  // x0 for a start from initial conditions (uic): IC= of capacitors and inductors, .ic node
  // voltages, switch ON/OFF; everything else 0.
  Vector initial_conditions() const;
  // Predicates at (t, x) from the guards, except that a predicate an auxiliary mode follows
  // (a switch's state, an ideal diode's mode) starts equal to that mode.
  padae::Predicates initial_predicates(double t, const Vector& x) const;
  // The initial conditions (IC=, .ic) that x does not keep, beyond ten times their tolerances
  // (rtol relative, the unknown's absolute one): after a uic start, those the circuit overrode.
  struct OverriddenInitialCondition {
    std::string name;  // "c1", or "v(a)" for a .ic node voltage
    double given, at_x;
    bool current;  // amperes, else volts
  };
  std::vector<OverriddenInitialCondition> overridden_initial_conditions(const Vector& x, double rtol,
                                                                        double default_atol) const;
  // initial_conditions() with the .nodeset voltages: where the operating point's Newton starts.
  Vector operating_point_guess() const;
  // While set, the .ic node voltages are held fixed (the operating point, as ngspice does).
  void hold_initial_voltages(bool hold) { holding_ = hold; }

  // Energy in capacitors and inductors at x; energy a jump dissipated (stored before + delivered
  // by sources during the jump - stored after).
  double stored_energy(const Vector& x) const;
  double jump_dissipation(const padae::EventRecord& event) const;

  // Connections of every device, for the structural checks: in any mode, or in mode p.
  std::vector<Edge> edges() const;
  std::vector<Edge> edges(const padae::Predicates& p) const;

 private:
  void hold_rows(const Vector& x, padae::Load& out) const;

  // The circuit and the arena are declared before devices_: the devices read their cards and
  // live in the arena.
  CircuitSpec circuit_;
  Unknowns unknowns_;
  DeviceArena device_memory_;
  std::vector<DevicePointer> devices_;
  // The devices asked per step for guards and kinks (with their first entry in the model's
  // vector) and time events (switches, junctions and sources among 1e5 resistors and
  // capacitors), and per Newton iteration for limits.
  struct NumberedDevice {
    const Device* device;
    int first;
  };
  std::vector<NumberedDevice> predicate_devices_;
  std::vector<NumberedDevice> kink_devices_;
  std::vector<const Device*> time_dependent_devices_;
  std::vector<const Device*> limiting_devices_;  // junctions
  bool constant_jacobian_ = true;
  padae::Pattern pattern_;
  std::vector<padae::UnknownKind> kinds_;
  std::vector<padae::JumpEntry> jump_entries_;
  std::vector<int> predicate_owners_;  // index in predicate_devices_ of each predicate
  int predicate_count_ = 0;
  int kink_count_ = 0;
  Tolerances tolerances_;
  ChargeReference charge_reference_;
  padae::Load reference_load_;  // scratch of measure_charges_from()
  std::map<int, double> held_nodes_;
  std::map<int, double> nodesets_;
  std::vector<std::vector<int>> held_row_slots_;  // value positions in each held row
  std::vector<int> held_diagonal_slots_;
  bool holding_ = false;
};

}  // namespace mna
