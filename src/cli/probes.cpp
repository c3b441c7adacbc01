#include "cli/probes.hpp"

#include <algorithm>
#include <cctype>

namespace padsim {

namespace {

std::string trim(std::string s) {
  auto space = [](unsigned char c) { return std::isspace(c) != 0; };
  s.erase(s.begin(), std::find_if_not(s.begin(), s.end(), space));
  s.erase(std::find_if_not(s.rbegin(), s.rend(), space).base(), s.end());
  return s;
}

int node_index(const mna::Model& model, const std::string& node, const std::string& probe) {
  const int index = model.find_node(node);
  if (index == -2) throw mna::ModelError("probe " + probe + ": no node '" + node + "' in the circuit");
  return index;
}

Probe voltage_probe(const mna::Model& model, const std::string& node, const std::string& reference) {
  const std::string name = "v(" + node + (reference.empty() ? "" : "," + reference) + ")";
  Probe p{name, node_index(model, node, name), mna::ground};
  if (!reference.empty()) p.minus = node_index(model, reference, name);
  return p;
}

Probe current_probe(const mna::Model& model, const std::string& element) {
  const std::string name = "i(" + element + ")";
  if (!model.unknowns().has_branch(element))
    throw mna::ModelError("probe " + name + ": '" + element +
                          "' has no branch current (V, L, E, H, B with V=, ideal switches and diodes have one)");
  return Probe{name, model.unknowns().branch(element), mna::ground};
}

}  // namespace

std::vector<Probe> parse_probes(const std::string& list, const mna::Model& model) {
  std::string text = list;
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  std::vector<Probe> probes;
  std::size_t position = 0;
  while (position < text.size()) {
    // One probe: letter, '(', arguments, ')'; commas inside the parentheses separate nodes.
    const std::size_t open = text.find('(', position), close = text.find(')', position);
    if (open == std::string::npos || close == std::string::npos || close < open)
      throw mna::ModelError("probe list '" + list + "': expected v(node), v(node,node) or i(element)");
    const std::string kind = trim(text.substr(position, open - position));
    std::string inside = text.substr(open + 1, close - open - 1);
    const std::size_t comma = inside.find(',');
    const std::string first = trim(inside.substr(0, comma));
    const std::string second = comma == std::string::npos ? "" : trim(inside.substr(comma + 1));
    if (kind == "v" && !first.empty()) probes.push_back(voltage_probe(model, first, second));
    else if (kind == "i" && !first.empty() && second.empty()) probes.push_back(current_probe(model, first));
    else throw mna::ModelError("probe '" + trim(text.substr(position, close - position + 1)) + "': expected v(node), v(node,node) or i(element)");
    position = text.find_first_not_of(" \t,", close + 1);
  }
  if (probes.empty()) throw mna::ModelError("empty probe list");
  return probes;
}

std::vector<Probe> requested_probes(const std::vector<netlist::OutputRequest>& requests, const mna::Model& model) {
  std::vector<Probe> probes;
  for (const auto& request : requests) {
    using Kind = netlist::OutputRequest::Kind;
    if (request.kind == Kind::all) return default_probes(model);
    if (request.kind == Kind::node_voltage) probes.push_back(voltage_probe(model, request.node, request.reference));
    else probes.push_back(current_probe(model, request.element));
  }
  return probes;
}

std::vector<Probe> default_probes(const mna::Model& model) {
  std::vector<Probe> probes;
  const mna::Unknowns& unknowns = model.unknowns();
  for (int i = 0; i < unknowns.size(); ++i)
    if (unknowns.category(i) == mna::UnknownCategory::node_voltage) probes.push_back({unknowns.label(i), i, mna::ground});
  for (const auto& element : model.circuit().elements)
    if (element.type == 'v' || element.type == 'l') probes.push_back(current_probe(model, element.name));
  return probes;
}

}  // namespace padsim
