// Fusion adaptation of the AST structs whose fields the grammar fills in sequence.
#pragma once

#include <optional>

#include <boost/fusion/include/adapt_struct.hpp>
#include <boost/spirit/home/x3/support/traits/optional_traits.hpp>

#include "netlist/ast.hpp"

// X3 (Boost 1.74) knows boost::optional only; the AST uses std::optional.
namespace boost::spirit::x3::traits {
template <typename T>
struct is_optional<std::optional<T>> : mpl::true_ {};
template <typename T>
struct build_optional<std::optional<T>> {
  using type = std::optional<T>;
};
template <typename T>
struct optional_value<std::optional<T>> : mpl::identity<T> {};
}  // namespace boost::spirit::x3::traits

BOOST_FUSION_ADAPT_STRUCT(netlist::ast::Assignment, name, value)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::TwoTerminal, name, positive, negative, value, parameters)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::Coupling, name, first, second, value)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::SourceSpec, kind, args, options)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::IndependentSource, name, positive, negative, specs)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::VoltageControlled, name, positive, negative,
                          control_positive, control_negative, gain)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::CurrentControlled, name, positive, negative, control, gain)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::Polynomial, name, positive, negative, dimension, arguments)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::Behavioral, name, positive, negative, quantity, expression)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::Diode, name, anode, cathode, model, area, off, parameters)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::Mosfet, name, drain, gate, source, bulk, model, parameters, off)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::VoltageSwitch, name, positive, negative, control_positive,
                          control_negative, model, state)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::CurrentSwitch, name, positive, negative, control, model,
                          state)
// The subcircuit is the last of the words; the parser moves it out of `nodes`.
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::Instance, name, nodes, parameters)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::ModelCard, name, type, parameters)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::Subcircuit, name, ports, parameters)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::TranCard, directive, step, stop, start, max_step, uic)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::NodeAssignment, node, reference, value)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::NodeValuesCard, directive, values)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::OptionsCard, directive, items)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::OutputItem, function, args)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::OutputCard, directive, items)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::TempCard, directive, value)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::GlobalCard, directive, nodes)
BOOST_FUSION_ADAPT_STRUCT(netlist::ast::Include, directive, path, section)
