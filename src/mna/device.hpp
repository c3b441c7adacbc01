// What a device is to the model: it allocates its unknowns, declares its Jacobian entries once,
// then loads f, q and their derivatives (Xyce-style: no step size, no method). Conditional
// devices also own predicates (guards and jump-matrix entries). Each device lives in its own
// file under devices/ and registers a factory for its element letter (gnucap-style).
#pragma once

#include <algorithm>
#include <functional>
#include <limits>
#include <memory>
#include <memory_resource>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "mna/circuit_spec.hpp"
#include "padae/integrator.hpp"

namespace mna {

using padae::Vector;

// Bad input found while building the model (unknown element, missing controlling source,
// structurally singular circuit): the command exits with status 2.
class ModelError : public std::runtime_error {
 public:
  explicit ModelError(const std::string& message, std::string element = "")
      : std::runtime_error(message), element_(std::move(element)) {}
  // An error in the .ic of a node.
  static ModelError at_initial_condition(const std::string& message, std::string node) {
    ModelError error(message);
    error.initial_condition_ = std::move(node);
    return error;
  }
  // The element at fault, where there is one: the command points at its card.
  const std::string& element() const { return element_; }
  // The node whose .ic is at fault, where it is one: the command points at that .ic.
  const std::string& initial_condition() const { return initial_condition_; }

 private:
  std::string element_;
  std::string initial_condition_;
};

constexpr int ground = -1;  // the index of the reference node: never an unknown
constexpr double infinity = std::numeric_limits<double>::infinity();

// internal_current: a current only its device reads (a floating capacitor's or diode junction's,
// devices/charge_branch.hpp); no element or probe names it, unlike a branch_current.
enum class UnknownCategory { node_voltage, internal_node, branch_current, internal_current, auxiliary };

// The unknowns of the model: node voltages first, then whatever devices allocate.
class Unknowns {
 public:
  // Index of a circuit node, created on first use; ground for "0" and "gnd".
  int node(const std::string& name);
  // Index of an existing circuit node, ground, or -2 when there is no such node.
  int find_node(const std::string& name) const;
  int add(std::string label, UnknownCategory category, std::string owner);
  // Index of the branch current of `element` (V, L, E, H, B with V=, ideal switch or diode).
  int branch(const std::string& element) const;
  bool has_branch(const std::string& element) const;

  int size() const { return static_cast<int>(labels_.size()); }
  const std::string& label(int unknown) const { return labels_.at(unknown); }  // "v(out)", "i(l1)"
  UnknownCategory category(int unknown) const { return categories_.at(unknown); }
  const std::string& owner(int unknown) const { return owners_.at(unknown); }  // node or element

 private:
  std::vector<std::string> labels_;
  std::vector<UnknownCategory> categories_;
  std::vector<std::string> owners_;
  std::unordered_map<std::string, int> nodes_, branches_;
};

// The value of an unknown in x; 0 for ground.
inline double value(const Vector& x, int unknown) { return unknown == ground ? 0.0 : x[unknown]; }

class Device;
// Where a model's devices live: one arena, in the order they are made, so that an evaluation
// streams through them instead of visiting objects scattered among their node names (1.1e5-
// unknown RC ladder: 34.8 s -> 26.3 s). The arena frees the memory; its owner destroys the
// devices first.
class DeviceArena {
 public:
  struct Destroy {
    void operator()(Device* device) const;
  };
  using Pointer = std::unique_ptr<Device, Destroy>;
  template <class Kind, class... Arguments>
  Pointer make(Arguments&&... arguments) {
    void* memory = memory_.allocate(sizeof(Kind), alignof(Kind));
    return Pointer(new (memory) Kind(std::forward<Arguments>(arguments)...));
  }

 private:
  std::pmr::monotonic_buffer_resource memory_;
};
using DevicePointer = DeviceArena::Pointer;

// Collects the Jacobian entries of all devices; once the pattern exists, every declared slot
// is overwritten with its position in the value arrays (or -1 when its row or column is ground).
class Stamper {
 public:
  Stamper(Unknowns& unknowns, const std::vector<DevicePointer>& devices)
      : unknowns_(unknowns), devices_(devices) {}
  Unknowns& unknowns() { return unknowns_; }
  // Another device by name (K reads its inductors), or nullptr.
  const Device* device(const std::string& name) const;

  void entry(int row, int column, int& slot) { declare(row, column, slot, false); }
  void charge_entry(int row, int column, int& slot) { declare(row, column, slot, true); }

  // The four entries a two-terminal conductance (or capacitance) touches.
  struct Block {
    int aa = -1, ab = -1, ba = -1, bb = -1;
  };
  void block(int a, int b, Block& slots) {
    entry(a, a, slots.aa), entry(a, b, slots.ab), entry(b, a, slots.ba), entry(b, b, slots.bb);
  }
  void charge_block(int a, int b, Block& slots) {
    charge_entry(a, a, slots.aa), charge_entry(a, b, slots.ab);
    charge_entry(b, a, slots.ba), charge_entry(b, b, slots.bb);
  }

  // Used by the model after all devices declared.
  padae::Pattern build_pattern(int size);
  std::vector<bool> charged_columns(int size) const;

 private:
  void declare(int row, int column, int& slot, bool charge);
  struct Declared {
    int row, column;
    int* slot;
    bool charge;
  };
  Unknowns& unknowns_;
  const std::vector<DevicePointer>& devices_;
  std::vector<Declared> declared_;
};

// Each charge a device loads, in the order loaded, at the state the model measures charges
// from (padae::System::measure_charges_from). Empty: charges are absolute.
struct ChargeReference {
  std::vector<double> charges;
  bool recording = false;  // the evaluation at the reference state fills `charges`
};

// One model evaluation as a device sees it.
class Evaluation {
 public:
  Evaluation(double t, const Vector& x, const padae::Predicates& p, padae::Load& out, ChargeReference& reference)
      : t(t), x(x), p(p), out_(out), reference_(reference) {}
  const double t;
  const Vector& x;
  const padae::Predicates& p;

  double value(int unknown) const { return mna::value(x, unknown); }
  bool jacobian() const { return out_.jacobian_requested; }
  void f(int row, double value) { if (row != ground) out_.f[row] += value; }
  // Each charge enters its row as its change from the reference: a row then sums changes and
  // rounds to their size, while a device's own rounding cancels between its two rows.
  void q(int row, double value) {
    if (row == ground) return;
    if (reference_.recording) {
      reference_.charges.push_back(value);
      return;
    }
    if (!reference_.charges.empty()) value -= reference_.charges.at(charges_loaded_++);
    out_.q[row] += value;
  }
  // How many charges the devices loaded (against the reference's count).
  std::size_t charges_loaded() const { return charges_loaded_; }
  // Derivatives count only when asked for: an evaluation without them must leave the arrays
  // as they are (a constant Jacobian is kept in them).
  void df(int slot, double value) { if (slot >= 0 && out_.jacobian_requested) out_.df_dx[slot] += value; }
  void dq(int slot, double value) { if (slot >= 0 && out_.jacobian_requested) out_.dq_dx[slot] += value; }
  void df(const Stamper::Block& b, double g) { df(b.aa, g), df(b.ab, -g), df(b.ba, -g), df(b.bb, g); }
  void dq(const Stamper::Block& b, double c) { dq(b.aa, c), dq(b.ab, -c), dq(b.ba, -c), dq(b.bb, c); }

 private:
  padae::Load& out_;
  ChargeReference& reference_;
  std::size_t charges_loaded_ = 0;
};

// How a device connects nodes, for the structural checks before a run.
enum class Connection {
  conductive,       // R, D, finite switches: a DC path
  capacitive,       // C: a path only in transient
  voltage_defined,  // V, E, H, B with V=: a DC path that fixes the voltage (loops are singular)
  inductive,        // L: a DC short (a loop with voltage sources is singular at DC)
  current_defined,  // I, F, G, B with I=: no path (but see current_source_connection)
};
struct Edge {
  int a, b;
  Connection connection;
  std::string element;
};

// A current source from a to b whose current reads the voltage of a or b (G1 a 0 a 0 1m,
// B1 a 0 I={v(a)/1k}: a conductance) ties that node down: conductive. Otherwise current-defined.
inline Connection current_source_connection(int a, int b, const std::vector<int>& unknowns_read) {
  const bool reads_own_node = std::any_of(unknowns_read.begin(), unknowns_read.end(),
                                          [&](int u) { return u != ground && (u == a || u == b); });
  return reads_own_node ? Connection::conductive : Connection::current_defined;
}

// A device keeps only what its evaluation reads; its name, node names and cold parameters stay
// on its card, which the model keeps for the device's lifetime. An evaluation streams through
// every device: a resistor is 48 bytes instead of 104 (1.1e5-unknown RC ladder: 23.1 s -> 19.5 s).
class Device {
 public:
  explicit Device(const ElementSpec& card) : card_(&card) {}
  virtual ~Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;
  const std::string& name() const { return card_->name; }

  // Its circuit nodes (from the card), internal nodes, branch currents, auxiliary unknowns.
  virtual void allocate(Unknowns& unknowns) { (void)unknowns; }
  // Jacobian entries (controlling branches of other devices are known by now).
  virtual void declare(Stamper& stamper) = 0;
  virtual void load(Evaluation& e) const = 0;
  virtual void edges(std::vector<Edge>& out) const = 0;
  // The connections in one mode (predicates p): an ideal switch or diode is a voltage-defined
  // branch when closed with RON = 0 and no connection when open with ROFF = infinite.
  virtual void mode_edges(const padae::Predicates& p, std::vector<Edge>& out) const { (void)p, edges(out); }

  // Whether its derivatives depend on the predicates alone (padae::System::constant_jacobian):
  // a linear element, a switch. A device that does not say so is taken to be nonlinear.
  virtual bool constant_jacobian() const { return false; }

  // Predicates, numbered from `first` in the model's vector (see PredicateDevice).
  virtual int predicate_count() const { return 0; }
  virtual std::string predicate_label(int local) const { return std::to_string(local); }
  virtual void number_predicates(int first) { (void)first; }
  virtual void guards(double t, const Vector& x, double* out) const { (void)t, (void)x, (void)out; }
  virtual void jump_entries(std::vector<padae::JumpEntry>& out) const { (void)out; }
  // Mode the auxiliary unknowns start in (switch ON/OFF); x0 entries of other unknowns are set
  // by the initial conditions.
  virtual void initial_auxiliaries(Vector& x0) const { (void)x0; }

  // Kinks (padae::System::kinks), written from out[0]: a junction's voltage, whose zero is where
  // its current turns off.
  virtual int kink_count() const { return 0; }
  virtual void kinks(const Vector& x, double* out) const { (void)x, (void)out; }

  // Newton's step from x to x_next as the device accepts it (padae::System::newton_step_fraction);
  // asked only of devices that say they limit.
  virtual bool limits_newton_steps() const { return false; }
  virtual double newton_step_fraction(const Vector& x, const Vector& x_next) const {
    (void)x, (void)x_next;
    return 1;
  }
  // padae::System::currents_converged for this device's currents; asked only of devices that
  // limit Newton's steps.
  virtual bool currents_converged(const Vector& x_before, const Vector& x_after, double rtol, double abstol) const {
    (void)x_before, (void)x_after, (void)rtol, (void)abstol;
    return true;
  }

  // Whether the device depends on time (an independent source): only such devices are asked
  // for time events, forcing rows and resolution steps.
  virtual bool time_dependent() const { return false; }
  virtual double next_time_event(double t) const { (void)t; return infinity; }
  // The rows the device's time dependence enters (appended): where its corners act. A device
  // with time events that lists none has its corners end the step (the safe side).
  virtual void forcing_rows(std::vector<int>& out) const { (void)out; }
  // The longest integration step that still resolves this device's own time dependence.
  virtual double resolution_step() const { return infinity; }
  // Whether the device's time dependence jumps at t (see SourceFunction::jumps_at).
  virtual bool jumps_at(double t) const { (void)t; return false; }

  // Energy accounting at jumps: stored energy, and energy delivered while `impulse` (the
  // integral of each unknown over the jump) passed.
  virtual double stored_energy(const Vector& x) const { (void)x; return 0; }
  virtual double delivered_energy(double t, const Vector& impulse) const { (void)t, (void)impulse; return 0; }

  // Initial condition (IC=) of a current, written into x0 for a uic start.
  virtual void initial_condition(Vector& x0) const { (void)x0; }
  // Initial condition (IC=) of a voltage: v(a) - v(b) = value at a uic start. The model solves
  // these together with .ic (model.cpp): written one by one, a capacitor between two nodes
  // would take whatever the other node held when its card came.
  struct InitialVoltage {
    int a, b;
    double value;
  };
  virtual std::optional<InitialVoltage> initial_voltage() const { return std::nullopt; }
  // The IC= given and the same quantity at x (a capacitor's voltage, an inductor's current),
  // with the unknown whose tolerance measures it: tells a start that kept it from one the
  // circuit overrode (a capacitor across a source). None without IC=.
  struct InitialConditionAt {
    double given, at_x;
    int unknown;
  };
  virtual std::optional<InitialConditionAt> initial_condition_at(const Vector& x) const {
    (void)x;
    return std::nullopt;
  }

 protected:
  const ElementSpec& card() const { return *card_; }

 private:
  const ElementSpec* card_;
};

// A device with predicates (switch, ideal diode, conditions of a B source) keeps where they start.
class PredicateDevice : public Device {
 public:
  using Device::Device;
  void number_predicates(int first) override { first_predicate_ = first; }
  int first_predicate() const { return first_predicate_; }

 private:
  int first_predicate_ = 0;
};

inline void DeviceArena::Destroy::operator()(Device* device) const { device->~Device(); }

// Factories keyed by element letter ("d:ideal" for the ideal diode model); they make the device
// in the arena from its card, which outlives it.
using DeviceFactory = std::function<DevicePointer(const ElementSpec&, const RunSettings&, DeviceArena&)>;
class DeviceRegistry {
 public:
  static DeviceRegistry& instance();
  void add(const std::string& key, DeviceFactory factory);
  const DeviceFactory* find(const std::string& key) const;

 private:
  std::vector<std::pair<std::string, DeviceFactory>> factories_;
};
// A static instance of this in a device's file registers it.
struct Registration {
  Registration(const std::string& key, DeviceFactory factory) {
    DeviceRegistry::instance().add(key, std::move(factory));
  }
};

// Model parameter lookup with a default.
double parameter(const ElementSpec& spec, const std::string& name, double fallback);

}  // namespace mna

namespace mna {
// Throws ModelError unless the element has exactly `count` nodes.
void require_nodes(const ElementSpec& spec, std::size_t count);
}  // namespace mna
