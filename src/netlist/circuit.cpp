#include "netlist/circuit.hpp"

#include <algorithm>

namespace netlist {

const FlatModel* FlatCircuit::find_model(const std::string& name) const {
  auto found = std::find_if(models.begin(), models.end(),
                            [&](const FlatModel& model) { return model.name == name; });
  return found == models.end() ? nullptr : &*found;
}

const FlatElement* FlatCircuit::find_element(const std::string& name) const {
  auto found = std::find_if(elements.begin(), elements.end(),
                            [&](const FlatElement& element) { return element.name == name; });
  return found == elements.end() ? nullptr : &*found;
}

const Option* FlatCircuit::find_option(const std::string& name) const {
  auto found = std::find_if(options.rbegin(), options.rend(),
                            [&](const Option& option) { return option.name == name; });
  return found == options.rend() ? nullptr : &*found;
}

}  // namespace netlist
