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

namespace {

// One character of netlist text as a diagnostic shows it, from text[at]: printable ASCII, and a
// UTF-8 sequence (lead and continuation bytes) of a character other than a C1 control, as they
// are; a tab as a tab where `tab` is kept; any other byte as \xNN.
struct Shown {
  std::size_t bytes;  // of the text
  std::string text;
};
Shown show(std::string_view text, std::size_t at, bool tab) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = byte(at);
  if ((c >= 0x20 && c < 0x7f) || (c == '\t' && tab)) return {1, std::string(1, text[at])};
  const std::size_t length = c >= 0xc2 && c < 0xe0 ? 2 : c >= 0xe0 && c < 0xf0 ? 3 : c >= 0xf0 && c < 0xf5 ? 4 : 0;
  bool sequence = length > 0 && at + length <= text.size() && !(c == 0xc2 && byte(at + 1) < 0xa0);
  for (std::size_t k = 1; sequence && k < length; ++k) sequence = (byte(at + k) & 0xc0) == 0x80;
  if (sequence) return {length, std::string(text.substr(at, length))};
  return {1, fmt::format("\\x{:02x}", c)};
}

std::string printable(std::string_view text) {
  std::string shown;
  for (std::size_t at = 0; at < text.size();) {
    const Shown character = show(text, at, false);
    shown += character.text;
    at += character.bytes;
  }
  return shown;
}

}  // namespace

std::string format(const Diagnostic& diagnostic) {
  static constexpr const char* severity_names[] = {"error", "warning", "note"};
  const char* severity = severity_names[static_cast<int>(diagnostic.severity)];
  const SourcePosition& begin = diagnostic.where.begin;
  const std::string message = printable(diagnostic.message);
  if (!begin.file) return fmt::format("{}: {}\n", severity, message);
  std::string text = fmt::format("{}:{}:{}: {}: {}\n", printable(begin.file->path), begin.line, begin.column,
                                 severity, message);
  std::string_view line = begin.file->line(begin.line);
  if (line.empty() && begin.line == 0) return text;
  // The line's characters, and those that the range's first and last bytes are in.
  std::vector<Shown> characters;
  const std::size_t first_byte = static_cast<std::size_t>(std::max(begin.column, 1) - 1);
  const std::size_t last_byte = first_byte + static_cast<std::size_t>(std::max(diagnostic.where.length, 1)) - 1;
  std::size_t first = 0, last = 0;
  for (std::size_t at = 0; at < line.size();) {
    // Past the range's first character only those shown are needed, and one more (for "...").
    if (at > first_byte && characters.size() > first + kShownCharacters) break;
    if (at <= first_byte) first = characters.size();
    if (at <= last_byte) last = characters.size();
    characters.push_back(show(line, at, true));
    at += characters.back().bytes;
  }
  if (first_byte >= line.size()) first = last = characters.size();  // just past the end
  const std::size_t from = first - std::min(first, kShownBefore);
  const std::size_t to = std::min(characters.size(), std::max(from + kShownCharacters, first + 1));
  std::string shown = from > 0 ? "..." : "", caret = from > 0 ? "   " : "";
  for (std::size_t k = from; k < to; ++k) {
    shown += characters[k].text;
    // A character of several bytes (UTF-8) is one column, an escape as many as it shows.
    const std::size_t width = characters[k].bytes > 1 ? 1 : characters[k].text.size();
    if (k < first) caret.append(characters[k].text == "\t" ? "\t" : std::string(width, ' '));
    else if (k == first) caret.append("^").append(width - 1, '~');
    else if (k <= last) caret.append(width, '~');
  }
  if (to < characters.size()) shown += "...";
  if (first >= to) caret += '^';
  return text + fmt::format("  {}\n  {}\n", shown, caret);
}

std::string quote(std::string_view text) {
  std::size_t at = 0;
  for (std::size_t k = 0; k < kQuotedCharacters && at < text.size(); ++k) at += show(text, at, false).bytes;
  std::string shown = "'";
  shown += printable(text.substr(0, at));
  shown += at < text.size() ? "...'" : "'";
  return shown;
}

}  // namespace netlist
