// Source positions kept from the text to every diagnostic.
#pragma once

#include <memory>
#include <string>

namespace netlist {

struct SourceFile;  // defined by the parser: path and text, shared by every position in it

struct SourcePosition {
  std::shared_ptr<const SourceFile> file;
  int line = 0;    // 1-based
  int column = 0;  // 1-based
};

struct SourceRange {
  SourcePosition begin;
  int length = 0;  // characters on the first line
};

}  // namespace netlist
