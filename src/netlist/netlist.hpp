// Public entry points of the netlist layer: text -> AST -> flat circuit.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "netlist/ast.hpp"
#include "netlist/circuit.hpp"
#include "netlist/source.hpp"

namespace netlist {

// Parse a netlist; includes are resolved relative to the including file. Returns the cards
// that parsed; errors (several per pass, recovering at the next card) go to `diagnostics`.
ast::Netlist parse_text(std::string text, std::string path, Diagnostics& diagnostics);
ast::Netlist parse_file(const std::filesystem::path& path, Diagnostics& diagnostics);

// A circuit whose subcircuits expand to more cards than this is refused (counted before any is
// built). Every card elaboration visits counts, once per instance of the body it is in: each
// element, each X card (even of an empty subcircuit), each model, parameter or other card; so
// it bounds the cards elaboration processes, not only the elements it builds.
inline constexpr std::size_t max_expanded_cards = 10'000'000;

// Evaluate parameters, expand subcircuits, check references. nullopt when any error occurred.
std::optional<FlatCircuit> elaborate(const ast::Netlist& netlist, Diagnostics& diagnostics,
                                     std::size_t max_cards = max_expanded_cards);

// parse_file then elaborate; nullopt if either reported an error.
std::optional<FlatCircuit> load(const std::filesystem::path& path, Diagnostics& diagnostics);

// The netlist as text that parses back to the same AST (positions aside).
std::string print(const ast::Netlist& netlist);
std::string print(const Expression& expression);

// The value of an engineering-notation number such as "10uF", "2.2meg", "1mil"; nullopt if the
// whole text is not one number (nan and inf are not numbers here).
std::optional<double> parse_number(std::string_view text);

}  // namespace netlist
