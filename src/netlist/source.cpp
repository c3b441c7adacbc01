#include "netlist/source.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace netlist {

SourceFile::SourceFile(std::string path_, std::string text_)
    : path(std::move(path_)), text(std::move(text_)) {
  line_starts.push_back(0);
  for (std::size_t i = 0; i < text.size(); ++i)
    if (text[i] == '\n') line_starts.push_back(i + 1);
}

std::string_view SourceFile::line(int number) const {
  if (number < 1 || static_cast<std::size_t>(number) > line_starts.size()) return {};
  std::size_t begin = line_starts[number - 1];
  std::size_t end = text.find('\n', begin);
  if (end == std::string::npos) end = text.size();
  if (end > begin && text[end - 1] == '\r') --end;
  return std::string_view(text).substr(begin, end - begin);
}

bool Diagnostics::add(Severity severity, SourceRange where, std::string message) {
  const SourcePosition& begin = where.begin;
  std::string key = fmt::format("{}:{}:{}:{}:{}", static_cast<const void*>(begin.file.get()),
                                begin.line, begin.column, static_cast<int>(severity), message);
  if (!seen_.insert(std::move(key)).second) return false;
  items_.push_back({severity, std::move(where), std::move(message)});
  return true;
}

void Diagnostics::error(SourceRange where, std::string message) {
  if (add(Severity::error, std::move(where), std::move(message))) ++error_count_;
}

void Diagnostics::warning(SourceRange where, std::string message) {
  add(Severity::warning, std::move(where), std::move(message));
}

void Diagnostics::note(SourceRange where, std::string message) {
  add(Severity::note, std::move(where), std::move(message));
}

std::string Diagnostics::to_string() const {
  std::string text;
  for (const auto& diagnostic : items_) text += format(diagnostic);
  return text;
}

std::string format(const Diagnostic& diagnostic) {
  static constexpr const char* severity_names[] = {"error", "warning", "note"};
  const char* severity = severity_names[static_cast<int>(diagnostic.severity)];
  const SourcePosition& begin = diagnostic.where.begin;
  if (!begin.file) return fmt::format("{}: {}\n", severity, diagnostic.message);
  std::string text = fmt::format("{}:{}:{}: {}: {}\n", begin.file->path, begin.line, begin.column,
                                 severity, diagnostic.message);
  std::string_view line = begin.file->line(begin.line);
  if (line.empty() && begin.line == 0) return text;
  // Tabs are kept in the caret line so that the caret lines up under tab-indented text.
  std::string caret;
  for (int i = 0; i + 1 < begin.column && i < static_cast<int>(line.size()); ++i)
    caret += line[i] == '\t' ? '\t' : ' ';
  caret += '^';
  caret.append(std::max(0, diagnostic.where.length - 1), '~');
  return text + fmt::format("  {}\n  {}\n", line, caret);
}

}  // namespace netlist
