// Waveform columns: v(node), v(node, reference) and i(element) read from the state vector.
#pragma once

#include <string>
#include <vector>

#include "mna/model.hpp"
#include "netlist/circuit.hpp"

namespace padsim {

struct Probe {
  std::string name;  // as in the CSV header: "v(out)", "v(a,b)", "i(l1)"
  int plus = mna::ground, minus = mna::ground;
  double value(const mna::Vector& x) const {
    return (plus == mna::ground ? 0.0 : x[plus]) - (minus == mna::ground ? 0.0 : x[minus]);
  }
};

// From a --probe list ("v(out),i(l1)", case-insensitive). Throws mna::ModelError naming the
// probe when its node or branch current does not exist.
std::vector<Probe> parse_probes(const std::string& list, const mna::Model& model);
// From .save / .print requests (an "all" request gives the default columns).
std::vector<Probe> requested_probes(const std::vector<netlist::OutputRequest>& requests, const mna::Model& model);
// All circuit node voltages, then the currents of V sources and inductors, in netlist order.
std::vector<Probe> default_probes(const mna::Model& model);

}  // namespace padsim
