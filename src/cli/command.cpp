#include "cli/command.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "cli/output/waveform_writer.hpp"
#include "cli/probes.hpp"
#include "mna/from_netlist.hpp"
#include "mna/start.hpp"
#include "mna/structure.hpp"
#include "netlist/netlist.hpp"

namespace padsim {

namespace {

using Clock = std::chrono::steady_clock;

void print_error(const std::string& message) { fmt::print(stderr, "padsim: error: {}\n", message); }

// What the run needs from the netlist and the command line.
struct RunSetup {
  netlist::FlatCircuit flat;
  mna::CircuitSpec circuit;
  mna::RunSettings settings;
  double tstart = 0;
  bool uic = false;
  padae::Options integrator;
  mna::Tolerances tolerances;
};

// .options reltol, abstol (currents), vntol (voltages), as ngspice names them; the command line
// overrides. --atol sets the absolute tolerance of every unknown.
void apply_tolerances(const netlist::FlatCircuit& flat, const CommandOptions& options, RunSetup& setup) {
  auto option = [&](const char* name, double fallback) {
    const netlist::Option* o = flat.find_option(name);
    return o && o->number ? *o->number : fallback;
  };
  setup.integrator.rtol = options.rtol.value_or(option("reltol", 1e-3));
  setup.tolerances.current = options.atol.value_or(option("abstol", 1e-12));
  setup.tolerances.voltage = options.atol.value_or(option("vntol", 1e-6));
  setup.integrator.atol = setup.tolerances.voltage;
}

// One CSV column set, written to every requested waveform writer.
class Waveforms {
 public:
  void add(std::unique_ptr<output::WaveformWriter> writer) { writers_.push_back(std::move(writer)); }
  void begin(const std::vector<Probe>& probes) {
    probes_ = probes;
    std::vector<std::string> names;
    for (const auto& p : probes) names.push_back(p.name);
    values_.resize(probes.size());
    for (auto& w : writers_) w->begin(names);
  }
  void row(double t, const mna::Vector& x) {
    for (std::size_t k = 0; k < probes_.size(); ++k) values_[k] = probes_[k].value(x);
    for (auto& w : writers_) w->row(t, values_);
  }
  bool differ(const mna::Vector& a, const mna::Vector& b) const {
    for (const auto& p : probes_)
      if (p.value(a) != p.value(b)) return true;
    return false;
  }
  void finish() {
    for (auto& w : writers_) w->finish();
  }

 private:
  std::vector<std::unique_ptr<output::WaveformWriter>> writers_;
  std::vector<Probe> probes_;
  std::vector<double> values_;
};

// --events: one line per predicate flip; the energy is that the whole event's jump dissipated.
class EventLog {
 public:
  explicit EventLog(const std::string& path) : file_(path) {
    if (!file_) throw std::runtime_error("cannot write the event log '" + path + "'");
    file_ << "time,element,predicate,from,to,jump_energy\n";
  }
  void write(const mna::Model& model, const padae::EventRecord& event, double energy) {
    for (const auto& flip : event.flips)
      file_ << fmt::format("{},{},{},{},{},{}\n", event.t, model.predicate_owner(flip.predicate).name(),
                           model.predicate_label(flip.predicate), int(flip.from), int(flip.to), energy);
  }

 private:
  std::ofstream file_;
};

// A progress line on a terminal, after the first second.
class Progress {
 public:
  Progress(bool enabled, double t_end) : enabled_(enabled && isatty(fileno(stderr))), t_end_(t_end) {}
  void update(double t) {
    if (!enabled_) return;
    const auto now = Clock::now();
    if (now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::milliseconds(250)) return;
    last_ = now;
    shown_ = true;
    fmt::print(stderr, "\rpadsim: t = {:.6g} s ({:.0f} %)", t, 100 * t / t_end_);
    std::fflush(stderr);
  }
  void clear() {
    if (shown_) fmt::print(stderr, "\r\033[K");
  }

 private:
  bool enabled_;
  double t_end_;
  bool shown_ = false;
  Clock::time_point start_ = Clock::now(), last_ = start_;
};

std::string blame(const mna::Model& model, int unknown) {
  if (unknown < 0 || unknown >= model.size()) return "";
  const auto& u = model.unknowns();
  switch (u.category(unknown)) {
    case mna::UnknownCategory::node_voltage: return fmt::format(" (node {})", u.owner(unknown));
    default: return fmt::format(" (element {}, unknown {})", u.owner(unknown), u.label(unknown));
  }
}

void print_statistics(const padae::Statistics& s, int unknowns, double wall) {
  fmt::print(stderr,
             "{{\"steps\": {}, \"rejected\": {}, \"newton_iterations\": {}, \"jacobians\": {}, "
             "\"lu_factorizations\": {}, \"events\": {}, \"jumps\": {}, \"unknowns\": {}, \"wall_s\": {:.6f}}}\n",
             s.steps, s.rejected_error_test + s.rejected_newton + s.rejected_domain, s.newton_iterations,
             s.jacobians, s.lu_factorizations, s.events, s.jumps, unknowns, wall);
}

}  // namespace

int run_command(const CommandOptions& options) {
  const auto wall_start = Clock::now();
  // --- input: netlist, circuit, model, structure, columns (errors: exit 2) ---
  netlist::Diagnostics diagnostics;
  std::optional<netlist::FlatCircuit> flat = netlist::load(options.netlist, diagnostics);
  for (const auto& d : diagnostics.all())
    if (d.severity == netlist::Severity::error || !options.quiet) fmt::print(stderr, "{}", netlist::format(d));
  if (!flat) return bad_input;

  RunSetup setup;
  if (!flat->tran && !options.tstop) {
    print_error("the netlist has no .tran card (give --tstop)");
    return bad_input;
  }
  setup.settings.tstop = options.tstop.value_or(flat->tran ? flat->tran->stop : 0);
  setup.settings.tstep = flat->tran && flat->tran->step > 0 ? flat->tran->step : setup.settings.tstop / 50;
  setup.tstart = flat->tran ? flat->tran->start : 0;
  setup.uic = flat->tran && flat->tran->use_initial_conditions;
  apply_tolerances(*flat, options, setup);
  setup.integrator.time_scale = setup.settings.tstop;
  if (flat->tran && flat->tran->max_step) setup.integrator.max_step = *flat->tran->max_step;

  std::unique_ptr<mna::Model> model;
  std::vector<Probe> probes;
  try {
    setup.circuit = mna::circuit_from_netlist(*flat);
    model = std::make_unique<mna::Model>(setup.circuit, setup.settings);
    model->set_tolerances(setup.tolerances);
    mna::check_structure(*model, setup.uic ? mna::StartKind::initial_conditions : mna::StartKind::operating_point);
    if (!options.probes.empty()) probes = parse_probes(options.probes, *model);
    else if (!flat->saves.empty()) probes = requested_probes(flat->saves, *model, setup.circuit);
    else probes = default_probes(*model, setup.circuit);
  } catch (const mna::ModelError& e) {
    print_error(e.what());
    return bad_input;
  }

  // --- outputs (cannot open: exit 2) ---
  Waveforms waveforms;
  std::unique_ptr<EventLog> event_log;
  std::string plot_csv = options.output;
  std::filesystem::path temporary_csv;
  try {
    if (!options.plot.empty() && (options.output.empty() || options.output == "-")) {
      // The plot reads a CSV file: write one next to the PNG's name when the CSV goes to stdout.
      temporary_csv = std::filesystem::temp_directory_path() / fmt::format("padsim-{}.csv", getpid());
      plot_csv = temporary_csv.string();
      waveforms.add(output::make_csv_writer(plot_csv));
      if (options.output == "-") waveforms.add(output::make_csv_writer("-"));
    } else {
      waveforms.add(output::make_csv_writer(options.output.empty() ? "-" : options.output));
    }
    if (!options.raw.empty()) waveforms.add(output::make_raw_writer(options.raw, !options.raw_ascii, flat->title));
    if (!options.events.empty()) event_log = std::make_unique<EventLog>(options.events);
    waveforms.begin(probes);
  } catch (const std::exception& e) {
    print_error(e.what());
    return bad_input;
  }

  // --- the run (failure: exit 1, waveform so far kept) ---
  const double t_end = setup.settings.tstop;
  padae::Integrator integrator(*model, setup.integrator);
  Progress progress(!options.quiet, t_end);
  auto fail = [&](double t, const std::string& why, int unknown) {
    progress.clear();
    waveforms.finish();
    print_error(fmt::format("simulation failed at t = {:.9g} s: {}{}", t, why, blame(*model, unknown)));
    if (options.stats) print_statistics(integrator.statistics(), model->size(),
                                        std::chrono::duration<double>(Clock::now() - wall_start).count());
    return simulation_failure;
  };
  auto emit = [&](double t, const mna::Vector& x) {
    if (t >= setup.tstart) waveforms.row(t, x);
  };
  // --grid: rows at tstart + k TSTEP strictly inside the last accepted step, from its polynomial
  // (after a restart at a corner or an event the polynomial is gone: those steps get none).
  auto grid_point = [&](long k) { return setup.tstart + static_cast<double>(k) * setup.settings.tstep; };
  long next_grid = 0;
  auto emit_grid = [&](double t_before, double t_after) {
    while (grid_point(next_grid) <= t_before) ++next_grid;
    for (; grid_point(next_grid) < t_after; ++next_grid) emit(grid_point(next_grid), integrator.interpolate(grid_point(next_grid)));
  };

  // A writer failing mid-run (disk full) ends the run like a simulation failure (exit 1): what
  // was written is kept.
  try {
    const mna::Start start = mna::find_start(*model, 0, setup.uic, setup.integrator);
    try {
      mna::check_mode_structure(*model, setup.uic ? mna::StartKind::initial_conditions : mna::StartKind::operating_point,
                                start.p);
    } catch (const mna::ModelError& e) {
      waveforms.finish();
      print_error(e.what());
      return bad_input;
    }
    if (!start.ok) return fail(0, "no initial operating point: " + start.message, start.worst_unknown);
    if (!integrator.initialize(0, start.x, start.p))
      return fail(0, integrator.failure().reason, integrator.failure().unknown);
    emit(0, integrator.state());

    while (integrator.time() < t_end) {
      const double t_before = integrator.time();
      const padae::StepOutcome outcome = integrator.step(t_end);
      switch (outcome.kind) {
        case padae::StepKind::failed:
          return fail(integrator.failure().t, integrator.failure().reason, integrator.failure().unknown);
        case padae::StepKind::event: {
          // Two rows at a discontinuity: the state just before and just after it.
          const padae::EventRecord& event = integrator.last_event();
          if (waveforms.differ(event.x_before, integrator.state())) emit(outcome.t, event.x_before);
          emit(outcome.t, integrator.state());
          if (event_log) event_log->write(*model, event, event.jumped ? model->jump_dissipation(event) : 0.0);
          break;
        }
        case padae::StepKind::accepted:
          if (options.grid) emit_grid(t_before, outcome.t);
          emit(outcome.t, integrator.state());
          break;
        case padae::StepKind::time_event:
        case padae::StepKind::stop: emit(outcome.t, integrator.state()); break;
      }
      progress.update(outcome.t);
    }
  } catch (const std::exception& e) {
    progress.clear();
    waveforms.finish();
    print_error(fmt::format("stopped at t = {:.9g} s: {}", integrator.time(), e.what()));
    return simulation_failure;
  }
  progress.clear();
  waveforms.finish();

  int status = success;
  if (!options.plot.empty()) {
    std::string error;
    if (!output::plot_png(plot_csv, options.plot, error)) {
      print_error("plot: " + error);
      status = simulation_failure;  // the waveform is complete, but not every requested output
    }
  }
  if (!temporary_csv.empty()) std::filesystem::remove(temporary_csv);
  if (options.stats) print_statistics(integrator.statistics(), model->size(),
                                      std::chrono::duration<double>(Clock::now() - wall_start).count());
  return status;
}

}  // namespace padsim
