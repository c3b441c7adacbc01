// The flat circuit that elaboration produces and src/mna consumes: subcircuits expanded,
// parameters evaluated, includes resolved. Every number is a resolved double; only B sources
// keep an expression (with parameters substituted: no ParameterRef is left in it).
//
// Naming, as ngspice flattens (but see `name`): node names are lower case, ground is "0"
// ("gnd" becomes "0" and stays global inside subcircuits); a node `n2` inside instance `x1`
// is "x1.n2", inside `x2` of `x1` it is "x1.x2.n2".
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "netlist/expression.hpp"
#include "netlist/position.hpp"
#include "netlist/source.hpp"

namespace netlist {

enum class ElementKind : char {
  resistor = 'r',
  capacitor = 'c',
  inductor = 'l',
  coupling = 'k',        // mutual inductance between two inductors
  voltage_source = 'v',
  current_source = 'i',
  vcvs = 'e',            // voltage-controlled voltage source
  cccs = 'f',            // current-controlled current source
  vccs = 'g',            // voltage-controlled current source
  ccvs = 'h',            // current-controlled voltage source
  behavioral = 'b',      // B source: V= or I= expression
  diode = 'd',
  mosfet = 'm',
  voltage_switch = 's',
  current_switch = 'w',
};

enum class WaveformKind { pulse, sin, exp, sffm, pwl };

// A transient waveform with its arguments as written, in ngspice's order; omitted trailing
// arguments are absent (their defaults depend on .tran, so the consumer applies them):
//   pulse: v1 v2 td tr tf pw per np     sin: vo va freq td theta phase
//   exp:   v1 v2 td1 tau1 td2 tau2      pwl: t1 v1 t2 v2 ... (even count, times non-decreasing)
struct Waveform {
  WaveformKind kind;
  std::vector<double> args;
  std::optional<double> repeat_from;  // pwl r=: repeat from this time point (0: whole sequence)
  std::optional<double> delay;        // pwl td=
  SourceRange where;
};

// What an independent V or I source delivers. `dc` is the DC value (0 if not written); with a
// waveform, the transient value is the waveform's. AC specifications are accepted and dropped.
struct SourceValue {
  double dc = 0.0;
  std::optional<Waveform> waveform;
};

struct FlatElement {
  ElementKind kind;
  // Hierarchical name, lower case: "r1" at top level, "x1.r1" inside instance x1 (ngspice
  // itself shows "r.x1.r1"; the kind is a field here, so the name needs no letter prefix).
  std::string name;
  // r c l d b v i: n+ n-.  e g: n+ n- nc+ nc-.  s: n+ n- nc+ nc-.  f h w: n+ n-.  k: none.
  // m: drain gate source bulk.
  std::vector<std::string> nodes;
  // r: ohms  c: farads  l: henries  k: coupling coefficient  e h: gain (V/V, V/A)
  // f g: gain (A/A, A/V)  d: area factor (1 if not written).  Unused by v i b s w.
  double value = 0.0;
  // f h w: {controlling voltage source}.  k: {inductor 1, inductor 2}. Hierarchical names.
  std::vector<std::string> controls;
  std::map<std::string, double> instance_parameters;  // m: L W AD AS PD PS NRD NRS M as written
  std::string model;                         // d s w m: the name of a FlatCircuit::models entry
  std::optional<double> initial_condition;   // c: IC= volts  l: IC= amps  d: IC= volts
  std::optional<bool> initially_on;          // s w: ON / OFF written after the model
  bool off = false;                          // d m: OFF (initial guess hint)
  SourceValue source;                        // v i
  bool behavioral_is_voltage = true;         // b: V= (true) or I= (false)
  ExpressionPtr expression;                  // b: the expression, parameters substituted
  SourceRange where;                         // the element's name on its card
};

enum class ModelType { diode, voltage_switch, current_switch, nmos, pmos };

struct ModelParameter {
  double value;
  SourceRange where;
};

// Parameter names are lower case and kept even when unknown (unknown ones were warned about).
// Known: diode IS N RS CJO (CJ0 written as given) VJ M TT BV IBV EG XTI FC IDEAL RON ROFF VFWD;
// sw VT VH RON ROFF; csw IT IH RON ROFF; nmos, pmos: ngspice's level-1 MOSFET parameters.
struct FlatModel {
  std::string name;  // lower case; "x1.dmod" for a model defined inside a subcircuit
  ModelType type;
  std::map<std::string, ModelParameter> parameters;
  SourceRange where;

  std::optional<double> get(const std::string& parameter) const {
    auto found = parameters.find(parameter);
    if (found == parameters.end()) return std::nullopt;
    return found->second.value;
  }
};

struct Transient {
  double step = 0.0;
  double stop = 0.0;
  double start = 0.0;
  std::optional<double> max_step;
  bool use_initial_conditions = false;  // UIC
  SourceRange where;
};

// .ic / .nodeset: v(node) = value, or v(node, reference) = value.
struct NodeValue {
  std::string node;
  std::string reference;  // empty: ground
  double value;
  SourceRange where;
};

// .options name[=value]: numeric values resolved, word values (method=gear) kept as text.
struct Option {
  std::string name;                  // lower case
  std::optional<double> number;      // name=number (or a bare flag: none of both)
  std::string word;                  // name=word, lower case
  SourceRange where;
};

// .save / .print / .probe: what to record.
struct OutputRequest {
  enum class Kind { node_voltage, branch_current, all } kind;
  std::string node, reference;  // node_voltage (reference empty: ground)
  std::string element;          // branch_current
  SourceRange where;
};

struct FlatCircuit {
  std::string title;
  std::vector<FlatElement> elements;  // in netlist order, subcircuits expanded in place
  std::vector<FlatModel> models;
  std::optional<Transient> tran;
  std::vector<NodeValue> initial_conditions;  // .ic
  std::vector<NodeValue> nodesets;            // .nodeset
  std::vector<Option> options;                // in order; a later one overrides an earlier one
  std::vector<OutputRequest> saves;
  std::optional<double> temperature;          // .temp, degrees Celsius
  SourceRange temperature_where;              // its value on the .temp card
  std::vector<Diagnostic> warnings;           // warnings and notes from parsing and elaboration

  const FlatModel* find_model(const std::string& name) const;
  const FlatElement* find_element(const std::string& name) const;
  // The last .options entry of that (lower case) name, if any.
  const Option* find_option(const std::string& name) const;
};

}  // namespace netlist
