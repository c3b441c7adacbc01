// Source text and the diagnostics that point into it.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "netlist/position.hpp"

namespace netlist {

struct SourceFile {
  SourceFile(std::string path, std::string text);

  std::string path;
  std::string text;
  std::vector<std::size_t> line_starts;  // offset of each line's first character

  // The text of a 1-based line without its line terminator; empty when out of range.
  std::string_view line(int number) const;
};

enum class Severity { error, warning, note };

struct Diagnostic {
  Severity severity;
  SourceRange where;  // where.begin.file is null for diagnostics about no particular text
  std::string message;
};

// Collects diagnostics of a whole parse/elaboration so that several errors are reported at once.
// The same message at the same place is kept once (a subcircuit body is elaborated once per
// instance, its errors are not).
class Diagnostics {
 public:
  void error(SourceRange where, std::string message);
  void warning(SourceRange where, std::string message);
  void note(SourceRange where, std::string message);

  bool has_errors() const { return error_count_ > 0; }
  int error_count() const { return error_count_; }
  const std::vector<Diagnostic>& all() const { return items_; }

  // All diagnostics, each as formatted by netlist::format.
  std::string to_string() const;

 private:
  bool add(Severity severity, SourceRange where, std::string message);

  std::vector<Diagnostic> items_;
  std::unordered_set<std::string> seen_;
  int error_count_ = 0;
};

// "file:line:column: error: message", then the source line and a caret under the range. Both
// are printable: control bytes, C1 controls and bytes that are no UTF-8 show as \xNN (tabs stay
// in the line, to align the caret). A line longer than kShownCharacters is shown from
// kShownBefore characters before the range on, "..." where it is cut.
constexpr std::size_t kShownCharacters = 120;
constexpr std::size_t kShownBefore = 40;
std::string format(const Diagnostic& diagnostic);

// Netlist text as a message quotes it: 'text', printable as format() shows it and cut after
// kQuotedCharacters characters, then "..." (an unexpected token may be a megabyte of binary).
constexpr std::size_t kQuotedCharacters = 60;
std::string quote(std::string_view text);

}  // namespace netlist
