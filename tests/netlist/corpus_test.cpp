// Every netlist of the repository (circuits/ and tests/, found at run time) parses and
// elaborates without errors, and its printout parses to the same AST. Deliberately broken
// netlists live in directories named invalid.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "netlist/netlist.hpp"

namespace {

namespace fs = std::filesystem;

std::vector<fs::path> netlists() {
  const std::set<std::string> extensions{".cir", ".sp", ".spice", ".net", ".ckt"};
  std::vector<fs::path> found;
  for (const char* root : {"circuits", "tests"}) {
    fs::path directory = fs::path(PADSIM_SOURCE_DIR) / root;
    if (!fs::exists(directory)) continue;
    for (auto it = fs::recursive_directory_iterator(directory); it != fs::recursive_directory_iterator(); ++it) {
      if (it->is_directory() && it->path().filename() == "invalid") {
        it.disable_recursion_pending();
        continue;
      }
      if (it->is_regular_file() && extensions.count(it->path().extension().string()))
        found.push_back(it->path());
    }
  }
  return found;
}

TEST(Corpus, EveryNetlistRoundTrips) {
  for (const fs::path& path : netlists()) {
    netlist::Diagnostics diagnostics;
    std::string printed = netlist::print(netlist::parse_file(path, diagnostics));
    auto reparsed = netlist::parse_text(printed, path.string(), diagnostics);
    EXPECT_FALSE(diagnostics.has_errors()) << path << "\n" << diagnostics.to_string();
    EXPECT_EQ(netlist::print(reparsed), printed) << path;
  }
}

TEST(Corpus, EveryNetlistParsesAndElaborates) {
  std::vector<fs::path> paths = netlists();
  EXPECT_GE(paths.size(), 6u);  // at least this directory's data
  for (const fs::path& path : paths) {
    netlist::Diagnostics diagnostics;
    auto circuit = netlist::load(path, diagnostics);
    EXPECT_TRUE(circuit) << path << "\n" << diagnostics.to_string();
  }
}

}  // namespace
