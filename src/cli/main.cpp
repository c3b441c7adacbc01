// padsim NETLIST [-o OUT.csv] [--probe "v(out),i(l1)"]... [--rtol R] [--atol A] [--tstop T] [--method M] [--stats]
//                [--events FILE] [--raw OUT.raw] [--ascii] [--plot OUT.png] [--quiet]
// The only translation unit that includes CLI11 (slow to compile).
#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "cli/command.hpp"
#include "netlist/netlist.hpp"

namespace {

// Numbers on the command line read like the netlist's: "1m", "2.5u", "1e-6".
CLI::Option* add_number(CLI::App& app, const std::string& name, std::optional<double>& target, const std::string& help) {
  return app.add_option_function<std::string>(
                name,
                [&target, name](const std::string& text) {
                  const std::optional<double> value = netlist::parse_number(text);
                  if (!value || !(*value > 0)) throw CLI::ValidationError(name, "expected a positive number, got '" + text + "'");
                  target = value;
                },
                help)
      ->type_name("NUMBER");
}

}  // namespace

int main(int argc, char** argv) {
  padsim::CommandOptions options;
  CLI::App app{"padsim: transient simulation of switched circuits with exact events and jumps"};
  app.add_option("netlist", options.netlist, "SPICE netlist with a .tran card")->required();
  app.add_option("-o,--output", options.output, "waveform CSV (default: standard output)");
  // Given again, --probe adds columns: CLI11 joins the lists with commas (splitting each at its
  // commas first, which the join undoes: "v(a,b)" stays one probe).
  app.add_option("--probe", options.probes,
                 "columns, e.g. \"v(out),v(a,b),i(l1)\"; repeated, the lists add up in order (default: .save/.print, "
                 "else all node voltages and V and L currents)")
      ->join(',');
  add_number(app, "--rtol", options.rtol, "relative tolerance (overrides .options reltol; default 1e-8, see the README)");
  add_number(app, "--atol", options.atol, "absolute tolerance of every unknown (overrides .options abstol and vntol)");
  add_number(app, "--tstop", options.tstop, "stop time (overrides .tran)");
  app.add_option_function<std::string>(
         "--method",
         [&options](const std::string& text) {
           options.method = padsim::parse_method(text);
           if (!options.method) throw CLI::ValidationError("--method", "expected gear or trap, got '" + text + "'");
         },
         "integration between events (overrides .options method): gear (BDF orders 1-5, the default) or trap "
         "(trapezoidal: keeps a lossless oscillation's amplitude; not for stiff circuits)")
      ->type_name("gear|trap");
  app.add_flag("--stats", options.stats, "print run statistics as one JSON object on stderr");
  app.add_option("--events", options.events, "CSV of every event: time, element, predicate, from, to, jump energy");
  app.add_option("--raw", options.raw, "ngspice raw file (binary)");
  app.add_flag("--ascii", options.raw_ascii, "write the raw file in ascii");
  app.add_option("--plot", options.plot, "PNG of the probed signals (gnuplot)");
  app.add_flag("-q,--quiet", options.quiet, "no warnings, no progress line");
  app.add_flag("--grid", options.grid,
               "also write rows on the .tran TSTEP grid: each is the BDF step from the step's start to "
               "the row's time (charges and fluxes within the step's local error, the other unknowns "
               "consistent with them)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return padsim::bad_input;
  }
  return padsim::run_command(options);
}
