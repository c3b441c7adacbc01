// A circuit's reference waveform for the benchmark report: SUNDIALS IDA on the equations padsim
// builds from the netlist (its mna::Model, a padae::System), from padsim's operating point (or
// the uic state), at a tight tolerance. It shares padsim's devices and start, not its
// integrator: IDA's own BDF, error test and step control, its root finder on the guards (the
// switch instants), a restart at every source corner and event (from a state made consistent by
// a Newton the model limits), and IDA's interpolant for the output. The report cross-checks it
// against ngspice at tight settings, which shares nothing with padsim.
//
// Rows: IDA's own steps, a uniform grid of TSTEP / refine from IDA's interpolant between them,
// the source corners, and both sides of every event: a linear interpolation of the reference is
// then accurate between rows, also where a smooth junction bends the solution within
// picoseconds, and exact at the corners and switch instants.
//
// Limits (measured): with a VCVS fixing a capacitor's node (sc_integrator) the consistent-start
// problem is singular in y' and the run stops at t0; on bridge_rectifier, whose floating load's
// common mode is held by junctions, IDA took 1e8 steps for 10 ms. The report uses it for the
// buck and boost converters.
//
// Usage: padsim_ida_reference NETLIST OUT.csv PROBES RTOL [REFINE]
//   PROBES as padsim's --probe ("v(out),i(l1)"); absolute tolerances 1e-3 RTOL V for node
//   voltages (the report's vntol rule) and 1e-12 A for currents (below it, Newton's test on a
//   junction's current meets the round-off of its node's KCL); REFINE 10.
// Exit 0 with the CSV; 1 with a message on stderr when IDA fails (rows so far kept); 2 on bad
// input.
#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "cli/output/waveform_writer.hpp"
#include "cli/probes.hpp"
#include "ida_run.hpp"
#include "mna/from_netlist.hpp"
#include "mna/model.hpp"
#include "mna/start.hpp"
#include "netlist/netlist.hpp"

namespace {

int reference(const std::string& netlist_path, const std::string& csv_path, const std::string& probe_list,
              double rtol, int refine) {
  netlist::Diagnostics diagnostics;
  const std::optional<netlist::FlatCircuit> flat = netlist::load(netlist_path, diagnostics);
  for (const auto& d : diagnostics.all())
    if (d.severity == netlist::Severity::error) fmt::print(stderr, "{}", netlist::format(d));
  if (!flat || !flat->tran) {
    fmt::print(stderr, "padsim_ida_reference: {}: no circuit with a .tran card\n", netlist_path);
    return 2;
  }
  const netlist::Transient& tran = *flat->tran;
  mna::RunSettings settings;
  settings.tstop = tran.stop;
  settings.tstep = tran.step > 0 ? tran.step : tran.stop / 50;
  settings.reltol = rtol;
  mna::Model model(mna::circuit_from_netlist(*flat), settings);
  mna::Tolerances tolerances;
  tolerances.voltage = 1e-3 * rtol;
  tolerances.current = 1e-12;
  model.set_tolerances(tolerances);
  const std::vector<padsim::Probe> probes = padsim::parse_probes(probe_list, model);

  padae::Options options;
  options.rtol = rtol;
  options.atol = tolerances.voltage;
  options.time_scale = tran.stop;
  const mna::Start start = mna::find_start(model, 0, tran.use_initial_conditions, options);
  if (!start.ok) {
    fmt::print(stderr, "padsim_ida_reference: no initial state: {}\n", start.message);
    return 1;
  }

  ida_bench::IdaSettings ida_settings;
  ida_settings.rtol = rtol;
  ida_settings.atol.resize(model.size());
  for (int i = 0; i < model.size(); ++i) ida_settings.atol[i] = model.absolute_tolerance(i, tolerances.voltage);
  // Algebraic unknowns are out of the error test, as in padsim: the consistent start leaves
  // their y' at 0, and a node that follows a source's ramp would fail the test on that alone.
  ida_settings.suppress_algebraic = true;
  ida_settings.consistent_start = true;
  ida_settings.max_steps = 10000000;
  // A junction turning on, without SPICE's limiting of its voltage, takes IDA's Newton more
  // than its default iterations and attempts.
  ida_settings.max_newton_iterations = 20;
  ida_settings.max_newton_failures = 100;
  ida_settings.max_error_test_failures = 100;
  ida_settings.max_initial_condition_iterations = 200;
  ida_settings.limited_newton_initial_conditions = true;
  ida_settings.initial_condition_tolerance = 1e-3;
  ida_bench::IdaRun ida(model, 0, start.x, start.p, tran.stop, ida_settings);

  auto csv = padsim::output::make_csv_writer(csv_path);
  std::vector<std::string> names;
  for (const auto& p : probes) names.push_back(p.name);
  csv->begin(names);
  std::vector<double> values(probes.size());
  auto row = [&](double t, const padae::Vector& x) {
    if (t < tran.start) return;
    for (std::size_t k = 0; k < probes.size(); ++k) values[k] = probes[k].value(x);
    csv->row(t, values);
  };
  row(0, ida.y());

  const double dt = settings.tstep / refine;
  const double same_instant = 1e-9 * dt;  // grid points this close to a written row are skipped
  long next_row = 1;
  auto grid = [&](long k) { return tran.start + static_cast<double>(k) * dt; };
  double corner = std::min(model.next_time_event(0), tran.stop);
  while (ida.ok() && ida.t() < tran.stop) {
    const double t_before = ida.t();
    const ida_bench::Outcome outcome = ida.step(corner);
    if (outcome == ida_bench::Outcome::failed) break;
    for (; grid(next_row) < ida.t() - same_instant; ++next_row)
      if (grid(next_row) > t_before + same_instant) row(grid(next_row), ida.interpolate(grid(next_row)));
    switch (outcome) {
      case ida_bench::Outcome::reached: row(ida.t(), ida.y()); break;
      case ida_bench::Outcome::stop:
        row(ida.t(), ida.y());
        if (ida.t() < tran.stop) {
          ida.restart(fmt::format("at the source corner t = {}", ida.t()));
          corner = std::min(model.next_time_event(ida.t()), tran.stop);
        }
        break;
      case ida_bench::Outcome::root: {
        const padae::Vector before = ida.y();
        int first = -1;
        row(ida.t(), before);
        if (!ida.event(first)) break;
        row(ida.t(), ida.y());
        if (!ida.charges_unchanged(ida.y()))
          throw std::runtime_error(fmt::format("the charge matrix changed at t = {}: IDA's residual assumes it "
                                               "constant", ida.t()));
        break;
      }
      case ida_bench::Outcome::failed: break;
    }
  }
  csv->finish();
  const ida_bench::Counters c = ida.counters();
  fmt::print(stderr, "{{\"steps\": {}, \"rejected\": {}, \"newton_iterations\": {}, \"jacobians\": {}}}\n", c.steps,
             c.rejected, c.newton, c.jacobians);
  if (!ida.ok()) {
    fmt::print(stderr, "padsim_ida_reference: {}\n", ida.failure());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    fmt::print(stderr, "usage: padsim_ida_reference NETLIST OUT.csv PROBES RTOL [REFINE]\n");
    return 2;
  }
  try {
    return reference(argv[1], argv[2], argv[3], std::atof(argv[4]), argc > 5 ? std::atoi(argv[5]) : 10);
  } catch (const std::exception& e) {
    fmt::print(stderr, "padsim_ida_reference: {}\n", e.what());
    return 1;
  }
}
