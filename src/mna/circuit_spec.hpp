// The flat circuit mna builds a predicate DAE from: elements with resolved numbers, lower-case
// names, and the run settings some defaults depend on. The netlist adapter (from_netlist.hpp)
// fills it from an elaborated netlist; tests fill it directly.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "netlist/expression.hpp"

namespace mna {

// A transient source function with ngspice's parameters in ngspice's order; omitted trailing
// parameters take ngspice's defaults (some depend on TSTEP and TSTOP, see waveform.hpp).
struct Waveform {
  enum class Shape { constant, pulse, sine, exponential, frequency_modulated, piecewise_linear };
  Waveform() = default;
  Waveform(Shape shape_of, std::vector<double> parameters_of, std::optional<double> repeat_from_of = std::nullopt)
      : shape(shape_of), parameters(std::move(parameters_of)), repeat_from(repeat_from_of) {}

  Shape shape = Shape::constant;
  std::vector<double> parameters;
  // PWL r=: after its last point the function repeats from this time point on.
  std::optional<double> repeat_from;
};

struct ElementSpec {
  char type = 0;                     // element letter: r c l k v i e f g h b d s w
  std::string name;                  // lower case, hierarchical ("x1.r1")
  std::vector<std::string> nodes;    // lower case; "0" and "gnd" are ground
  double value = 0;                  // R, C, L value; K coupling; E, F, G, H gain; V, I DC value;
                                     // M: +1 NMOS, -1 PMOS (ngspice's type sign)
  std::optional<double> initial_condition;  // IC=: capacitor voltage, inductor current
  std::vector<std::string> controls; // F, H, W: controlling element; K: the two inductors
  Waveform waveform;                 // V, I: transient function (constant: the DC value)
  netlist::ExpressionPtr expression; // B: V= or I= expression
  bool expression_is_current = false;
  std::map<std::string, double> model;  // D, S, W, M: .model parameters, lower-case names
  std::map<std::string, double> instance_parameters;  // M: L W AD AS PD PS NRD NRS M as written
  double area = 1;                   // D: area factor
  std::optional<bool> initially_on;  // S, W: ON / OFF on the instance line
};

struct CircuitSpec {
  std::vector<ElementSpec> elements;
  std::map<std::string, double> initial_voltages;  // .ic v(node)=value, lower-case node names
  std::map<std::string, double> nodesets;          // .nodeset v(node)=value: operating-point guesses

  ElementSpec& add(std::string name, std::vector<std::string> nodes, double value = 0) {
    // The type is the name's first letter, as on a SPICE card.
    ElementSpec& element = elements.emplace_back();
    element.type = name.empty() ? char(0) : name[0];
    element.name = std::move(name);
    element.nodes = std::move(nodes);
    element.value = value;
    return element;
  }
};

// What the run adds to the circuit: source defaults use TSTEP and TSTOP, the diode's breakdown
// knee is matched to RELTOL (as ngspice does).
struct RunSettings {
  double tstep = 0;
  double tstop = 0;
  double reltol = 1e-3;
};

}  // namespace mna
