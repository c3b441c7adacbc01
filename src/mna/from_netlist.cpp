#include "mna/from_netlist.hpp"

#include <algorithm>

#include "mna/device.hpp"

namespace mna {

namespace {

Waveform waveform_from(const netlist::Waveform& w) {
  using Kind = netlist::WaveformKind;
  Waveform out;
  out.parameters = w.args;
  switch (w.kind) {
    case Kind::pulse: out.shape = Waveform::Shape::pulse; break;
    case Kind::sin: out.shape = Waveform::Shape::sine; break;
    case Kind::exp: out.shape = Waveform::Shape::exponential; break;
    case Kind::sffm: out.shape = Waveform::Shape::frequency_modulated; break;
    case Kind::pwl:
      out.shape = Waveform::Shape::piecewise_linear;
      out.repeat_from = w.repeat_from;
      if (w.delay) {
        for (std::size_t k = 0; k < out.parameters.size(); k += 2) out.parameters[k] += *w.delay;
        if (out.repeat_from) *out.repeat_from += *w.delay;
      }
      break;
  }
  return out;
}

// The element's model's parameters into spec; the model's type, one of `expected`.
netlist::ModelType copy_model(const netlist::FlatCircuit& flat, const netlist::FlatElement& element,
                              std::initializer_list<netlist::ModelType> expected, ElementSpec& spec) {
  const netlist::FlatModel* model = nullptr;
  for (const auto& m : flat.models)
    if (m.name == element.model) model = &m;
  if (!model) throw ModelError("element '" + element.name + "': no model '" + element.model + "'");
  if (std::find(expected.begin(), expected.end(), model->type) == expected.end())
    throw ModelError("element '" + element.name + "': model '" + element.model + "' has the wrong type");
  for (const auto& [name, parameter] : model->parameters) spec.model[name] = parameter.value;
  return model->type;
}

}  // namespace

CircuitSpec circuit_from_netlist(const netlist::FlatCircuit& flat) {
  using Kind = netlist::ElementKind;
  CircuitSpec circuit;
  for (const auto& element : flat.elements) {
    ElementSpec& spec = circuit.elements.emplace_back();
    spec.type = static_cast<char>(element.kind);
    spec.name = element.name;
    spec.nodes = element.nodes;
    spec.value = element.value;
    spec.controls = element.controls;
    spec.initially_on = element.initially_on;
    switch (element.kind) {
      case Kind::capacitor:
      case Kind::inductor: spec.initial_condition = element.initial_condition; break;
      case Kind::voltage_source:
      case Kind::current_source:
        spec.value = element.source.dc;
        if (element.source.waveform) spec.waveform = waveform_from(*element.source.waveform);
        break;
      case Kind::behavioral:
        spec.expression = element.expression;
        spec.expression_is_current = !element.behavioral_is_voltage;
        break;
      case Kind::diode:
        spec.area = element.value;
        copy_model(flat, element, {netlist::ModelType::diode}, spec);
        break;
      case Kind::mosfet: {
        const auto type = copy_model(flat, element, {netlist::ModelType::nmos, netlist::ModelType::pmos}, spec);
        spec.value = type == netlist::ModelType::nmos ? 1 : -1;
        spec.instance_parameters = element.instance_parameters;
        break;
      }
      case Kind::voltage_switch: copy_model(flat, element, {netlist::ModelType::voltage_switch}, spec); break;
      case Kind::current_switch: copy_model(flat, element, {netlist::ModelType::current_switch}, spec); break;
      default: break;
    }
  }
  for (const auto& ic : flat.initial_conditions) {
    if (!ic.reference.empty() && ic.reference != "0")
      throw ModelError(".ic v(" + ic.node + ", " + ic.reference + "): only node-to-ground initial voltages are supported");
    circuit.initial_voltages[ic.node] = ic.value;
  }
  for (const auto& guess : flat.nodesets) {
    if (!guess.reference.empty() && guess.reference != "0")
      throw ModelError(".nodeset v(" + guess.node + ", " + guess.reference + "): only node-to-ground guesses are supported");
    circuit.nodesets[guess.node] = guess.value;
  }
  return circuit;
}

}  // namespace mna
