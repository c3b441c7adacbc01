// The padsim command without its argument parsing (main.cpp): load the netlist, build the
// model, check it, start, integrate step by step, stream the waveform.
#pragma once

#include <optional>
#include <string>

#include "padae/integrator.hpp"

namespace padsim {

struct CommandOptions {
  std::string netlist;
  std::string output = "-";   // CSV; "-" is standard output
  std::string probes;         // "v(out),i(l1)" (every --probe's list); empty: .save/.print, else the default columns
  std::optional<double> rtol, atol, tstop;
  std::optional<padae::Method> method;  // overrides .options method
  bool stats = false;
  std::string events;         // event log CSV
  std::string raw;            // ngspice raw file
  bool raw_ascii = false;
  std::string plot;           // PNG
  bool quiet = false;
  bool grid = false;          // also rows on the .tran TSTEP grid, interpolated within steps
};

// Exit codes of the command. Bad input includes a circuit whose equations are singular (named
// by the structural checks, or linear and singular at the start). SIGTERM, SIGINT and SIGHUP stop
// the run after the current step: the rows so far are written, then padsim ends by the signal.
enum ExitCode { success = 0, simulation_failure = 1, bad_input = 2 };

// "gear" (or "bdf"), "trap" (or "trapezoidal"); nullopt for anything else.
std::optional<padae::Method> parse_method(const std::string& name);

// Runs the command; messages go to stderr. Returns the exit code.
int run_command(const CommandOptions& options);

}  // namespace padsim
