// libFuzzer target: any text is parsed and, if it parses, elaborated and printed; the printed
// netlist must parse again without errors. Crashes, hangs and sanitizer reports are failures.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "netlist/netlist.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  netlist::Diagnostics diagnostics;
  netlist::ast::Netlist parsed = netlist::parse_text(text, "fuzz.cir", diagnostics);
  for (const netlist::Diagnostic& diagnostic : diagnostics.all()) netlist::format(diagnostic);
  if (diagnostics.has_errors()) return 0;
  netlist::elaborate(parsed, diagnostics);
  std::string printed = netlist::print(parsed);
  netlist::Diagnostics again;
  netlist::parse_text(printed, "fuzz.cir", again);
  if (again.has_errors()) {
    fprintf(stderr, "printed netlist does not parse:\n%s\n%s", printed.c_str(),
            again.to_string().c_str());
    std::abort();
  }
  return 0;
}
