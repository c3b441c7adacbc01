// The netlist layer's flat circuit as mna's CircuitSpec: element kinds to type letters,
// .model parameters copied onto each element, waveforms and .ic carried over.
#pragma once

#include "mna/circuit_spec.hpp"
#include "netlist/circuit.hpp"

namespace mna {

// Throws ModelError for what mna cannot simulate (PWL r=, .ic between two nodes, a model of
// the wrong type).
CircuitSpec circuit_from_netlist(const netlist::FlatCircuit& flat);

}  // namespace mna
