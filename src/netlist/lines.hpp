// The line structure of SPICE text, before any card is parsed: the title line, `*` comment
// lines, `;` and `$ ` inline comments, `+` continuation lines, .control/.endc blocks and .end.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "netlist/position.hpp"
#include "netlist/source.hpp"

namespace netlist {

// One card: its physical lines joined (continuations with a blank in place of the `+`),
// comments removed, with the map back to positions in the file.
struct LogicalLine {
  struct Piece {
    std::size_t offset;  // in text, where this physical line's content starts
    int line, column;    // of that content in the file
  };
  std::shared_ptr<const SourceFile> file;
  std::string text;
  std::vector<Piece> pieces;

  SourcePosition position(std::size_t offset) const;
  // The range [first, last) of text, clipped to the physical line where it begins.
  SourceRange range(std::size_t first, std::size_t last) const;
};

struct SplitFile {
  std::string title;  // only when the file has a title line
  SourceRange title_where;
  std::vector<LogicalLine> cards;
};

// Splits a file into cards. The title is taken from the first line if `has_title`; reading
// stops at .end; .control blocks are skipped with a note.
SplitFile split_lines(const std::shared_ptr<const SourceFile>& file, bool has_title,
                      Diagnostics& diagnostics);

}  // namespace netlist
