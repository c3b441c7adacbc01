#include "netlist/lines.hpp"

#include <algorithm>
#include <cctype>
#include <string_view>

namespace netlist {

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// The card's text with every blank a space or a tab, the blanks the grammar skips: a form feed or
// vertical tab taken into a name would not survive printing (the line ends are trimmed of them).
// Same length, so that columns stay right.
std::string with_plain_blanks(std::string_view content) {
  std::string text(content);
  for (char& c : text)
    if (is_blank(c) && c != '\t') c = ' ';
  return text;
}

// The directive of a line whose content starts with '.', lower case ("control", "end", ...).
std::string directive_of(std::string_view content) {
  std::string directive;
  if (content.empty() || content[0] != '.') return directive;
  for (std::size_t i = 1; i < content.size() && std::isalnum(static_cast<unsigned char>(content[i]));
       ++i)
    directive += static_cast<char>(std::tolower(static_cast<unsigned char>(content[i])));
  return directive;
}

// The line without its inline comment: from ';', or from a '$' that stands alone as a word
// start ("$ comment"), so that '$' inside a name is kept.
std::string_view strip_inline_comment(std::string_view line) {
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (line[i] == ';') return line.substr(0, i);
    if (line[i] == '$' && (i == 0 || is_blank(line[i - 1])) &&
        (i + 1 == line.size() || is_blank(line[i + 1])))
      return line.substr(0, i);
  }
  return line;
}

}  // namespace

SourcePosition LogicalLine::position(std::size_t offset) const {
  auto piece = std::upper_bound(pieces.begin(), pieces.end(), offset,
                                [](std::size_t o, const Piece& p) { return o < p.offset; });
  if (piece != pieces.begin()) --piece;
  return {file, piece->line, piece->column + static_cast<int>(offset - piece->offset)};
}

SourceRange LogicalLine::range(std::size_t first, std::size_t last) const {
  auto piece = std::upper_bound(pieces.begin(), pieces.end(), first,
                                [](std::size_t o, const Piece& p) { return o < p.offset; });
  std::size_t piece_end = piece == pieces.end() ? text.size() : piece->offset;
  last = std::min(std::max(last, first), piece_end);
  return {position(first), static_cast<int>(last - first)};
}

SplitFile split_lines(const std::shared_ptr<const SourceFile>& file, bool has_title,
                      Diagnostics& diagnostics) {
  SplitFile result;
  int line_count = static_cast<int>(file->line_starts.size());
  int first = 1;
  if (has_title) {
    std::string_view title = file->line(1);
    result.title = std::string(title);
    result.title_where = {{file, 1, 1}, static_cast<int>(title.size())};
    first = 2;
  }
  SourceRange open_control;  // where an unterminated .control started
  bool in_control = false;
  for (int number = first; number <= line_count; ++number) {
    std::string_view line = strip_inline_comment(file->line(number));
    std::size_t start = 0;
    while (start < line.size() && is_blank(line[start])) ++start;
    std::size_t end = line.size();
    while (end > start && is_blank(line[end - 1])) --end;
    if (start == end) continue;
    std::string_view content = line.substr(start, end - start);
    SourceRange where{{file, number, static_cast<int>(start) + 1}, static_cast<int>(content.size())};
    std::string directive = directive_of(content);
    if (in_control) {
      if (directive == "endc") in_control = false;
      continue;
    }
    if (content[0] == '*') continue;
    if (directive == "control") {
      diagnostics.note(where, "the .control block is skipped: padsim runs no ngspice scripts");
      open_control = where;
      in_control = true;
      continue;
    }
    if (directive == "end") break;
    if (content[0] == '+') {
      if (result.cards.empty()) {
        diagnostics.error({where.begin, 1}, "continuation line '+' without a card to continue");
        continue;
      }
      LogicalLine& card = result.cards.back();
      card.text += ' ';
      card.pieces.push_back({card.text.size(), number, where.begin.column + 1});
      card.text += with_plain_blanks(content.substr(1));
      continue;
    }
    LogicalLine card;
    card.file = file;
    card.text = with_plain_blanks(content);
    card.pieces.push_back({0, number, where.begin.column});
    result.cards.push_back(std::move(card));
  }
  if (in_control) diagnostics.error(open_control, ".control without .endc");
  return result;
}

}  // namespace netlist
