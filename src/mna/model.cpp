#include "mna/model.hpp"

#include <algorithm>
#include <cmath>
#include <cctype>
#include <numeric>
#include <span>
#include <unordered_set>

namespace mna {

// ---- Unknowns -------------------------------------------------------------------------------

int Unknowns::node(const std::string& name) {
  const int found = find_node(name);
  return found != -2 ? found : add("v(" + name + ")", UnknownCategory::node_voltage, name);
}

int Unknowns::find_node(const std::string& name) const {
  if (name == "0" || name == "gnd") return ground;
  auto it = nodes_.find(name);
  return it == nodes_.end() ? -2 : it->second;
}

int Unknowns::add(std::string label, UnknownCategory category, std::string owner) {
  if (category == UnknownCategory::node_voltage) nodes_.emplace(owner, size());
  if (category == UnknownCategory::branch_current) branches_.emplace(owner, size());
  labels_.push_back(std::move(label));
  categories_.push_back(category);
  owners_.push_back(std::move(owner));
  return size() - 1;
}

bool Unknowns::has_branch(const std::string& element) const { return branches_.contains(element); }

int Unknowns::branch(const std::string& element) const {
  if (auto it = branches_.find(element); it != branches_.end()) return it->second;
  throw ModelError("element '" + element +
                   "' has no branch current (the controlling element must be a voltage source, "
                   "inductor or other element with a current unknown)");
}

// ---- Stamper --------------------------------------------------------------------------------

void Stamper::declare(int row, int column, int& slot, bool charge) {
  slot = -1;
  if (row == ground || column == ground) return;
  declared_.push_back({row, column, &slot, charge});
}

const Device* Stamper::device(const std::string& name) const {
  for (const auto& d : devices_)
    if (d->name() == name) return d.get();
  return nullptr;
}

padae::Pattern Stamper::build_pattern(int size) {
  std::vector<std::pair<int, int>> entries;
  entries.reserve(declared_.size());
  for (const auto& d : declared_) entries.emplace_back(d.row, d.column);
  padae::Pattern pattern(size, entries);
  for (const auto& d : declared_) *d.slot = pattern.index(d.row, d.column);
  return pattern;
}

std::vector<bool> Stamper::charged_columns(int size) const {
  std::vector<bool> charged(size, false);
  for (const auto& d : declared_)
    if (d.charge) charged[d.column] = true;
  return charged;
}

// ---- Registry -------------------------------------------------------------------------------

DeviceRegistry& DeviceRegistry::instance() {
  static DeviceRegistry registry;
  return registry;
}

void DeviceRegistry::add(const std::string& key, DeviceFactory factory) {
  factories_.emplace_back(key, std::move(factory));
}

const DeviceFactory* DeviceRegistry::find(const std::string& key) const {
  for (const auto& [k, factory] : factories_)
    if (k == key) return &factory;
  return nullptr;
}

double parameter(const ElementSpec& spec, const std::string& name, double fallback) {
  auto it = spec.model.find(name);
  return it == spec.model.end() ? fallback : it->second;
}

// ---- Model ----------------------------------------------------------------------------------

namespace {

std::string registry_key(const ElementSpec& spec) {
  std::string key(1, static_cast<char>(std::tolower(static_cast<unsigned char>(spec.type))));
  if (key == "d" && parameter(spec, "ideal", 0) != 0) key += ":ideal";
  return key;
}

}  // namespace

Model::Model(CircuitSpec circuit, const RunSettings& settings) : circuit_(std::move(circuit)) {
  // Circuit nodes first, in order of appearance, so that v(...) unknowns come first.
  for (const auto& spec : circuit_.elements)
    for (const auto& n : spec.nodes) unknowns_.node(n);
  // What one element's values or connections get wrong names it.
  auto for_element = [](const std::string& name, auto&& action) {
    try {
      action();
    } catch (const ModelError& e) {
      if (!e.element().empty()) throw;
      throw ModelError(e.what(), name);
    }
  };
  std::unordered_set<std::string> names;
  for (const auto& spec : circuit_.elements) {
    for_element(spec.name, [&] {
      if (!names.insert(spec.name).second) throw ModelError("element '" + spec.name + "' is defined twice");
      const DeviceFactory* factory = DeviceRegistry::instance().find(registry_key(spec));
      if (!factory) throw ModelError("element '" + spec.name + "': unsupported element type");
      devices_.push_back((*factory)(spec, settings, device_memory_));
    });
  }
  for (std::size_t k = 0; k < devices_.size(); ++k)
    for_element(circuit_.elements[k].name, [&] { devices_[k]->allocate(unknowns_); });

  Stamper stamper(unknowns_, devices_);
  for (std::size_t k = 0; k < devices_.size(); ++k)
    for_element(circuit_.elements[k].name, [&] { devices_[k]->declare(stamper); });
  for (const auto& [name, value] : circuit_.initial_voltages) {
    const int n = find_node(name);
    if (n == -2) throw ModelError(".ic names node '" + name + "', which is not in the circuit");
    if (n != ground) held_nodes_[n] = value;
  }
  for (const auto& [name, value] : circuit_.nodesets) {
    const int n = find_node(name);
    if (n == -2) throw ModelError(".nodeset names node '" + name + "', which is not in the circuit");
    if (n != ground) nodesets_[n] = value;
  }
  // Held rows become v - v_ic = 0: their diagonal must exist (it always does, see Pattern).
  pattern_ = stamper.build_pattern(size());

  const std::vector<bool> charged = stamper.charged_columns(size());
  kinds_.resize(size());
  for (int i = 0; i < size(); ++i) {
    if (unknowns_.category(i) == UnknownCategory::auxiliary)
      kinds_[i] = padae::UnknownKind::auxiliary;
    else
      kinds_[i] = charged[i] ? padae::UnknownKind::differential : padae::UnknownKind::algebraic;
  }

  for (const auto& device : devices_) {
    Device* d = device.get();
    if (d->time_dependent()) time_dependent_devices_.push_back(d);
    if (d->limits_newton_steps()) limiting_devices_.push_back(d);
    if (d->kink_count() > 0) {
      kink_devices_.push_back({d, kink_count_});
      kink_count_ += d->kink_count();
    }
    constant_jacobian_ = constant_jacobian_ && d->constant_jacobian();
    if (d->predicate_count() == 0) continue;
    d->number_predicates(predicate_count_);
    predicate_owners_.insert(predicate_owners_.end(), d->predicate_count(), static_cast<int>(predicate_devices_.size()));
    predicate_devices_.push_back({d, predicate_count_});
    predicate_count_ += d->predicate_count();
    d->jump_entries(jump_entries_);
  }

  // Positions of every entry in each held row, to overwrite the row during the operating point.
  for (const auto& [n, value] : held_nodes_) {
    std::vector<int> slots;
    for (int column = 0; column < size(); ++column)
      if (int s = pattern_.find(n, column); s >= 0) slots.push_back(s);
    held_row_slots_.push_back(std::move(slots));
    held_diagonal_slots_.push_back(pattern_.index(n, n));
  }
}

padae::EvalStatus Model::load(double t, const Vector& x, const padae::Predicates& p, padae::Load& out) {
  Evaluation e(t, x, p, out, charge_reference_);
  for (const auto& d : devices_) d->load(e);
  if (!charge_reference_.recording && !charge_reference_.charges.empty() &&
      e.charges_loaded() != charge_reference_.charges.size())
    throw std::logic_error("the devices loaded " + std::to_string(e.charges_loaded()) + " charges, " +
                           std::to_string(charge_reference_.charges.size()) + " at the charges' reference");
  if (holding_) hold_rows(x, out);
  // Outside a device's domain (sqrt of a negative voltage, an overflowing exponential): say so,
  // and padae cuts the step instead of factoring garbage.
  auto finite = [](const std::vector<double>& values) {
    return Eigen::Map<const Vector>(values.data(), static_cast<Eigen::Index>(values.size())).allFinite();
  };
  if (!out.f.allFinite() || !out.q.allFinite()) return padae::EvalStatus::outside_domain;
  if (out.jacobian_requested && !(finite(out.df_dx) && finite(out.dq_dx))) return padae::EvalStatus::outside_domain;
  return padae::EvalStatus::ok;
}

bool Model::measure_charges_from(double t, const Vector& x, const padae::Predicates& p) {
  charge_reference_.charges.clear();
  charge_reference_.recording = true;
  reference_load_.f.setZero(size());
  reference_load_.q.setZero(size());
  load(t, x, p, reference_load_);
  charge_reference_.recording = false;
  return true;
}

void Model::hold_rows(const Vector& x, padae::Load& out) const {
  std::size_t k = 0;
  for (const auto& [n, value] : held_nodes_) {
    out.f[n] = x[n] - value;
    out.q[n] = 0;
    if (out.jacobian_requested) {
      for (int s : held_row_slots_[k]) out.df_dx[s] = out.dq_dx[s] = 0;
      out.df_dx[held_diagonal_slots_[k]] = 1;
    }
    ++k;
  }
}

padae::EvalStatus Model::guards(double t, const Vector& x, Vector& out) const {
  for (const auto& [d, first] : predicate_devices_) d->guards(t, x, out.data() + first);
  for (int k = 0; k < predicate_count_; ++k)
    if (!std::isfinite(out[k])) return padae::EvalStatus::outside_domain;
  return padae::EvalStatus::ok;
}

void Model::jump_matrix(double, const Vector&, const padae::Predicates&,
                        std::vector<padae::JumpEntry>& out) const {
  out.insert(out.end(), jump_entries_.begin(), jump_entries_.end());
}

double Model::next_time_event(double t) const {
  double next = infinity;
  for (const Device* d : time_dependent_devices_) next = std::min(next, d->next_time_event(t));
  return next;
}

bool Model::time_event_rows(double t, std::vector<int>& rows) const {
  const double corner = next_time_event(t);
  if (corner == infinity) return true;
  for (const Device* d : time_dependent_devices_) {
    if (d->next_time_event(t) != corner) continue;
    const std::size_t before = rows.size();
    d->forcing_rows(rows);
    if (rows.size() == before) return false;  // not said where it acts: the corner may bend anything
  }
  return true;
}

bool Model::source_jumps_at(double t) const {
  return std::any_of(time_dependent_devices_.begin(), time_dependent_devices_.end(),
                     [&](const Device* d) { return d->jumps_at(t); });
}

double Model::resolution_step() const {
  double step = infinity;
  for (const Device* d : time_dependent_devices_) step = std::min(step, d->resolution_step());
  return step;
}

void Model::kinks(const Vector& x, Vector& out) const {
  for (const auto& [d, first] : kink_devices_) d->kinks(x, out.data() + first);
}

double Model::newton_step_fraction(const Vector& x, const Vector& x_next) const {
  double fraction = 1;
  for (const Device* d : limiting_devices_) fraction = std::min(fraction, d->newton_step_fraction(x, x_next));
  return fraction;
}

double Model::absolute_tolerance(int unknown, double) const {
  switch (unknowns_.category(unknown)) {
    case UnknownCategory::node_voltage:
    case UnknownCategory::internal_node: return tolerances_.voltage;
    case UnknownCategory::branch_current:
    case UnknownCategory::internal_current: return tolerances_.current;
    case UnknownCategory::auxiliary: return 1.0;  // a 0/1 mode, never integrated
  }
  return tolerances_.voltage;
}

bool Model::currents_converged(const Vector& x_before, const Vector& x_after, double rtol) const {
  for (const Device* d : limiting_devices_)
    if (!d->currents_converged(x_before, x_after, rtol, tolerances_.current)) return false;
  return true;
}

int Model::find_node(const std::string& name) const { return unknowns_.find_node(name); }

const Device& Model::predicate_owner(int predicate) const {
  return *predicate_devices_.at(predicate_owners_.at(predicate)).device;
}

std::string Model::predicate_label(int predicate) const {
  const auto& [owner, first] = predicate_devices_.at(predicate_owners_.at(predicate));
  return owner->predicate_label(predicate - first);
}

namespace {

// Node voltages in x0 from conditions v(a) - v(b) = value, the earlier winning where they
// conflict (a loop of them that does not add up): a weighted union-find, each node's voltage
// an offset from its tree's root, ground (index `unknowns`) always a root. A tree without ground
// has its root at 0 V. Nodes under no condition keep x0's value.
void apply_initial_voltages(std::span<const Device::InitialVoltage> conditions, int unknowns, Vector& x0) {
  const int ground_slot = unknowns;
  std::vector<int> parent(static_cast<std::size_t>(unknowns) + 1);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<double> offset(parent.size(), 0.0);  // v(node) - v(parent)
  std::vector<char> conditioned(parent.size(), 0);
  const auto slot = [&](int node) { return node == ground ? ground_slot : node; };
  // The root of node's tree, with offset[node] then relative to it.
  const auto find = [&](int node) {
    int root = node;
    double sum = 0;
    while (parent[root] != root) sum += offset[root], root = parent[root];
    for (int k = node; parent[k] != root;) {  // path compression
      const int next = parent[k];
      const double rest = sum - offset[k];
      offset[k] = sum;
      parent[k] = root;
      sum = rest;
      k = next;
    }
    return root;
  };
  for (const auto& [a_node, b_node, value] : conditions) {
    const int a = slot(a_node), b = slot(b_node);
    conditioned[a] = conditioned[b] = 1;
    const int root_a = find(a), root_b = find(b);
    if (root_a == root_b) continue;  // fixed by earlier conditions
    // v(a) = v(root_a) + offset[a] and v(b) = v(root_b) + offset[b], with v(a) - v(b) = value.
    if (root_a == ground_slot) {
      parent[root_b] = root_a;
      offset[root_b] = offset[a] - value - offset[b];
    } else {
      parent[root_a] = root_b;
      offset[root_a] = offset[b] + value - offset[a];
    }
  }
  for (int node = 0; node < unknowns; ++node)
    if (conditioned[node]) {
      find(node);
      x0[node] = node == parent[node] ? 0.0 : offset[node];
    }
}

}  // namespace

Vector Model::initial_conditions() const {
  Vector x0 = Vector::Zero(size());
  for (const auto& d : devices_) d->initial_auxiliaries(x0);
  for (const auto& d : devices_) d->initial_condition(x0);
  // A device's IC= before .ic, which it overrides where they conflict (as in SPICE).
  std::vector<Device::InitialVoltage> voltages;
  for (const auto& d : devices_)
    if (const auto voltage = d->initial_voltage()) voltages.push_back(*voltage);
  for (const auto& [n, value] : held_nodes_) voltages.push_back({n, ground, value});
  apply_initial_voltages(voltages, size(), x0);
  return x0;
}

std::vector<Model::OverriddenInitialCondition> Model::overridden_initial_conditions(const Vector& x, double rtol,
                                                                                 double default_atol) const {
  std::vector<OverriddenInitialCondition> overridden;
  auto check = [&](std::string name, double given, double at_x, int unknown) {
    const double tolerance = rtol * std::max(std::abs(given), std::abs(at_x)) + absolute_tolerance(unknown, default_atol);
    if (std::abs(at_x - given) > 10 * tolerance)
      overridden.push_back({std::move(name), given, at_x, unknowns_.category(unknown) != UnknownCategory::node_voltage});
  };
  for (const auto& d : devices_)
    if (const auto at = d->initial_condition_at(x)) check(d->name(), at->given, at->at_x, at->unknown);
  for (const auto& [n, value] : held_nodes_) check(unknowns_.label(n), value, x[n], n);
  return overridden;
}

Vector Model::operating_point_guess() const {
  Vector x = initial_conditions();
  for (const auto& [n, value] : nodesets_)
    if (!held_nodes_.contains(n)) x[n] = value;
  return x;
}

padae::Predicates Model::initial_predicates(double t, const Vector& x) const {
  Vector values = Vector::Zero(predicate_count_);
  guards(t, x, values);
  padae::Predicates p(predicate_count_);
  for (int k = 0; k < predicate_count_; ++k) p[k] = values[k] > 0;
  for (const auto& entry : jump_entries_) p[entry.predicate] = x[entry.row] > 0.5;
  return p;
}

double Model::stored_energy(const Vector& x) const {
  double energy = 0;
  for (const auto& d : devices_) energy += d->stored_energy(x);
  return energy;
}

double Model::jump_dissipation(const padae::EventRecord& event) const {
  double delivered = 0;
  for (const auto& d : devices_) delivered += d->delivered_energy(event.t, event.impulse);
  return stored_energy(event.x_before) + delivered - stored_energy(event.x_after);
}

std::vector<Edge> Model::edges() const {
  std::vector<Edge> all;
  for (const auto& d : devices_) d->edges(all);
  return all;
}

std::vector<Edge> Model::edges(const padae::Predicates& p) const {
  std::vector<Edge> all;
  for (const auto& d : devices_) d->mode_edges(p, all);
  return all;
}

}  // namespace mna

namespace mna {
void require_nodes(const ElementSpec& spec, std::size_t count) {
  if (spec.nodes.size() != count)
    throw ModelError("element '" + spec.name + "' needs " + std::to_string(count) + " nodes, has " +
                     std::to_string(spec.nodes.size()));
}
}  // namespace mna
