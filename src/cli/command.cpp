#include "cli/command.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <regex>
#include <set>
#include <span>

#include "cli/output/waveform_writer.hpp"
#include "cli/probes.hpp"
#include "mna/from_netlist.hpp"
#include "mna/start.hpp"
#include "mna/structure.hpp"
#include "netlist/netlist.hpp"
#include "netlist/source.hpp"

namespace padsim {

namespace {

using Clock = std::chrono::steady_clock;

void print_error(const std::string& message) { fmt::print(stderr, "padsim: error: {}\n", message); }

// reltol when neither the netlist nor --rtol gives one. Not SPICE's 1e-3: SPICE's default run
// owes its accuracy to its step cap, TSTEP (its default TMAX), which holds its error on a
// switched converter near 1e-5 of a signal's range whatever reltol is. padsim's step has no
// such cap, and at reltol 1e-3 the errors its local tests let through add up over the periods
// to 1e-3 ... 2e-2 of the range (a Cuk converter: 1.7e-2). At 1e-6 they stay near SPICE's
// default run's, in a tenth of its time; at 1e-8 they are a tenth of it or less on the
// converters of the benchmark report (a boost's, summed over 50 periods, 0.10 of it), in
// 0.15 to 0.4 of its time.
constexpr double kDefaultRtol = 1e-8;

// .options reltol, abstol (currents), vntol (voltages), as ngspice names them; the command line
// overrides. --atol sets the absolute tolerance of every unknown. Returns false, having printed
// the error, for a tolerance that is not positive.
bool apply_tolerances(const netlist::FlatCircuit& flat, const CommandOptions& options, padae::Options& integrator,
                      mna::Tolerances& tolerances) {
  bool positive = true;
  auto option = [&](const char* name, double fallback) {
    const netlist::Option* o = flat.find_option(name);
    if (!o) return fallback;
    if (!o->number || !(*o->number > 0)) {
      const std::string given = o->number ? fmt::format("{}", *o->number) : o->word.empty() ? "no value" : "'" + o->word + "'";
      fmt::print(stderr, "{}", netlist::format(netlist::Diagnostic{netlist::Severity::error, o->where,
                                                                   fmt::format("{} must be a positive number, got {}", name, given)}));
      positive = false;
      return fallback;
    }
    return *o->number;
  };
  integrator.rtol = options.rtol.value_or(option("reltol", kDefaultRtol));
  // Unless given, vntol keeps SPICE's ratio to reltol (1 uV at reltol 1e-3), up to SPICE's
  // value: fixed, it stopped a tighter reltol at nodes that move by microvolts (an op-amp
  // macromodel's pole node, whose error its gain of 1e5 carries to the output, stayed 1e-2 of
  // the output's range off at any reltol). abstol stays: currents take reltol relative to their
  // peak (peak_floor below), and 1 pA scaled down too made a forward converter's diode, turning
  // off into its leakage, fail at reltol 1e-8.
  const double spice_ratio = std::min(1.0, std::max(integrator.rtol, padae::kSmallestRtol) / 1e-3);
  tolerances.current = options.atol.value_or(option("abstol", 1e-12));
  tolerances.voltage = options.atol.value_or(option("vntol", 1e-6 * spice_ratio));
  if (!positive) return false;
  if (integrator.rtol < padae::kSmallestRtol && !options.quiet)
    fmt::print(stderr, "padsim: warning: reltol {} is below what double precision resolves; using {:.2g}\n",
               integrator.rtol, padae::kSmallestRtol);
  integrator.atol = tolerances.voltage;
  // SPICE's vntol is reltol / 1000 of a 1 V signal; every unknown gets that ratio to its own
  // scale: abstol's 1 pA, sized for IC currents, would hold an amp-scale inductor current
  // passing through zero to a millionth of what its voltages get (a boost converter resolved a
  // 2 ps L / R_off mode at every diode turn-off, 40 steps a period).
  integrator.peak_floor = 1e-3;
  return true;
}

// .options method=gear|trap, as ngspice names them; --method overrides. padsim's default is gear
// (BDF), not ngspice's trap: switched circuits are stiff, and BDF damps what they excite.
// Returns false, having printed the error, for an unknown method.
bool apply_method(const netlist::FlatCircuit& flat, const CommandOptions& options, padae::Options& integrator) {
  if (options.method) {
    integrator.method = *options.method;
    return true;
  }
  const netlist::Option* o = flat.find_option("method");
  if (!o) return true;
  if (const std::optional<padae::Method> method = parse_method(o->word)) {
    integrator.method = *method;
    return true;
  }
  fmt::print(stderr, "{}", netlist::format(netlist::Diagnostic{
                               netlist::Severity::error, o->where,
                               "unknown integration method '" + o->word + "' (expected gear or trap)"}));
  return false;
}

// The .options padsim reads are reltol, abstol, vntol, method (above) and temp, tnom (below).
// SPICE's controls of its own Newton iteration, step and output have no meaning for padsim's
// integrator and are passed over quietly, as ngspice passes over others' options; any other name
// is warned of (a misspelt reltol would otherwise run at the default unseen).
void warn_of_unknown_options(const netlist::FlatCircuit& flat) {
  static const std::set<std::string, std::less<>> read = {"reltol", "abstol", "vntol", "method", "temp", "tnom"};
  static const std::set<std::string, std::less<>> spice_own = {
      "gmin",   "itl1",  "itl2",     "itl3",     "itl4",     "itl5",     "itl6",         "trtol",      "chgtol",
      "maxord", "xmu",   "pivtol",   "pivrel",   "gminsteps", "srcsteps", "noopiter",    "ramptime",   "rshunt",
      "cshunt", "klu",   "sparse",   "numdgt",   "acct",     "noacct",   "list",         "nomod",      "nopage",
      "node",   "opts",  "interp",   "warn",     "maxwarns", "savecurrents", "keepopinfo", "norefvalue", "seed"};
  for (const netlist::Option& option : flat.options)
    if (!read.contains(option.name) && !spice_own.contains(option.name))
      fmt::print(stderr, "{}", netlist::format(netlist::Diagnostic{netlist::Severity::warning, option.where,
                                                                   "option '" + option.name + "' is unknown to padsim and ignored"}));
}

// padsim's junctions (Shockley diodes, MOSFETs) are modelled at 27 C, their nominal temperature
// too. A netlist that asks for another (.temp, .options temp= or tnom=) while it has them is
// refused: their currents would be another circuit's. Without them nothing depends on it.
// Returns false, having printed the error.
bool check_temperature(const netlist::FlatCircuit& flat) {
  const auto junction = std::find_if(flat.elements.begin(), flat.elements.end(), [&](const netlist::FlatElement& e) {
    if (e.kind == netlist::ElementKind::mosfet) return true;
    if (e.kind != netlist::ElementKind::diode) return false;
    const netlist::FlatModel* model = flat.find_model(e.model);
    return !(model && model->get("ideal").value_or(0) != 0);
  });
  if (junction == flat.elements.end()) return true;
  bool nominal = true;
  auto refuse = [&](const std::string& asked, const netlist::SourceRange& where) {
    fmt::print(stderr, "{}", netlist::format(netlist::Diagnostic{
                                 netlist::Severity::error, where,
                                 fmt::format("{}: padsim models its diodes and MOSFETs ({} among them) at 27 C only",
                                             asked, junction->name)}));
    nominal = false;
  };
  if (flat.temperature && *flat.temperature != 27) refuse(fmt::format(".temp {} C", *flat.temperature), flat.temperature_where);
  for (const char* name : {"temp", "tnom"}) {
    const netlist::Option* o = flat.find_option(name);
    if (o && !(o->number && *o->number == 27))
      refuse(o->number ? fmt::format("{}={} C", name, *o->number) : fmt::format("{}={}", name, o->word), o->where);
  }
  return nominal;
}

// One CSV column set, written to every requested waveform writer.
class Waveforms {
 public:
  void add(std::unique_ptr<output::WaveformWriter> writer) { writers_.push_back(std::move(writer)); }
  void begin(const std::vector<Probe>& probes) {
    probes_ = probes;
    std::vector<std::string> names;
    for (const auto& p : probes) {
      names.push_back(p.name);
      for (int unknown : {p.plus, p.minus})
        if (unknown != mna::ground && std::find(read_.begin(), read_.end(), unknown) == read_.end()) read_.push_back(unknown);
    }
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
  // The unknowns the columns read.
  std::span<const int> unknowns_read() const { return read_; }

 private:
  std::vector<std::unique_ptr<output::WaveformWriter>> writers_;
  std::vector<Probe> probes_;
  std::vector<double> values_;
  std::vector<int> read_;
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

// Why a source's detail is finer than the integrator can resolve where it is (a few ulps of t,
// 1e-24 of the run near t = 0), if it is: a stop time far beyond the sources' time scale (a
// 10 us PULSE with TSTOP 1e300 s). Each source's first corners from 0, and the steps its
// periods ask for (a sine's) at the stop time, are checked; empty when they are resolved. Corners
// that go on past the first kCornersChecked repeat (a PULSE, a PWL with r=): their closest pair
// is checked against the resolution at the stop time too (a 2e-20 s PULSE period with TSTOP 1 ms
// ran on for ever, writing gigabytes of rows).
std::string unresolved_source_detail(const mna::Model& model, const padae::Options& options, double tstop) {
  constexpr int kCornersChecked = 1000;
  const double resolution_at_end = padae::time_resolution(tstop, options);
  for (const auto& device : model.devices()) {
    if (!device->time_dependent()) continue;
    if (const double step = device->resolution_step(); step < resolution_at_end)
      return fmt::format("the stop time {:g} s is too long for {}'s detail: the steps that resolve it ({:.3g} s) are "
                         "below the time resolution the run has at its end ({:.3g} s)",
                         tstop, device->name(), step, resolution_at_end);
    double previous = 0, closest = mna::infinity;
    int corners = 0;
    for (; corners < kCornersChecked; ++corners) {
      const double corner = device->next_time_event(previous);
      if (!(corner <= tstop)) break;
      if (const double resolution = padae::time_resolution(corner, options); corner - previous < resolution)
        return fmt::format("the stop time {:g} s is too long for {}'s detail: its corners at {:g} s and {:g} s are closer "
                           "than the time resolution the run has there ({:.3g} s)",
                           tstop, device->name(), previous, corner, resolution);
      if (corners > 0) closest = std::min(closest, corner - previous);
      previous = corner;
    }
    if (corners == kCornersChecked && device->next_time_event(previous) <= tstop && closest < resolution_at_end)
      return fmt::format("the stop time {:g} s is too long for {}'s detail: its corners repeat {:.3g} s apart, closer "
                         "than the time resolution the run has at its end ({:.3g} s)",
                         tstop, device->name(), closest, resolution_at_end);
  }
  return "";
}

// Where in the netlist an mna error is: its element's card, or the .ic of its node (the last,
// which is the one in force); null where it is about no card.
const netlist::SourceRange* card_at_fault(const netlist::FlatCircuit& flat, const mna::ModelError& e) {
  const netlist::SourceRange* where = nullptr;
  if (!e.initial_condition().empty()) {
    for (const netlist::NodeValue& ic : flat.initial_conditions)
      if (ic.node == e.initial_condition()) where = &ic.where;
  } else if (const netlist::FlatElement* element = e.element().empty() ? nullptr : flat.find_element(e.element())) {
    where = &element->where;
  }
  return where && where->begin.file ? where : nullptr;
}

std::string blame(const mna::Model& model, int unknown) {
  if (unknown < 0 || unknown >= model.size()) return "";
  const auto& u = model.unknowns();
  switch (u.category(unknown)) {
    case mna::UnknownCategory::node_voltage: return fmt::format(" (node {})", u.owner(unknown));
    default: return fmt::format(" (element {}, unknown {})", u.owner(unknown), u.label(unknown));
  }
}

// The integrator's failure messages number predicates ("predicates 0, 3"); name their elements
// and conditions too: "predicates 0 (b1: v(x)>0), 3 (s1: on)".
std::string name_predicates(const mna::Model& model, const std::string& reason) {
  static const std::regex list("(predicates? )([0-9]+(?:, [0-9]+)*)");
  std::smatch match;
  if (!std::regex_search(reason, match, list)) return reason;
  std::string named;
  const std::string numbers = match[2].str();
  static const std::regex number("[0-9]+");
  for (auto it = std::sregex_iterator(numbers.begin(), numbers.end(), number); it != std::sregex_iterator(); ++it) {
    const int k = std::stoi(it->str());
    if (!named.empty()) named += ", ";
    named += it->str();
    if (k >= 0 && k < model.predicate_count())
      named += fmt::format(" ({}: {})", model.predicate_owner(k).name(), model.predicate_label(k));
  }
  return match.prefix().str() + match[1].str() + named + match.suffix().str();
}

// SIGTERM, SIGINT, SIGHUP: the run stops after the current step, the rows so far are written,
// and padsim then dies of the same signal (so that shells and make see why it ended).
std::atomic<int> stop_signal{0};
extern "C" void on_stop_signal(int signal) { stop_signal.store(signal); }

class StopSignals {
 public:
  StopSignals() {
    for (int s : signals_) previous_[index(s)] = std::signal(s, on_stop_signal);
  }
  ~StopSignals() {
    for (int s : signals_) std::signal(s, previous_[index(s)]);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  static int received() { return stop_signal.load(); }
  // Re-raises the signal with its default action (ends the process).
  static void die_of(int signal) {
    std::signal(signal, SIG_DFL);
    std::raise(signal);
  }

 private:
  static constexpr int signals_[3] = {SIGTERM, SIGINT, SIGHUP};
  static int index(int s) { return s == SIGTERM ? 0 : s == SIGINT ? 1 : 2; }
  void (*previous_[3])(int) = {};
};

// output: the Newton work of rows written inside steps (Integrator::output_statistics).
void print_statistics(const padae::Statistics& s, const padae::Statistics& output, int unknowns, double t_end,
                      double wall) {
  fmt::print(stderr,
             "{{\"steps\": {}, \"rejected\": {}, \"rejected_error_test\": {}, \"rejected_newton\": {}, "
             "\"rejected_domain\": {}, \"retaken_at_kinks\": {}, \"newton_iterations\": {}, \"jacobians\": {}, "
             "\"lu_factorizations\": {}, \"events\": {}, \"time_events\": {}, \"jumps\": {}, "
             "\"output_newton_iterations\": {}, \"output_lu_factorizations\": {}, \"unsolved_points\": {}, "
             "\"output_unsolved_points\": {}, \"unresolved_steps\": {}, \"unknowns\": {}, \"t_end\": {}, \"wall_s\": {:.6f}}}\n",
             s.steps, s.rejected_error_test + s.rejected_newton + s.rejected_domain + s.retaken_at_kinks,
             s.rejected_error_test, s.rejected_newton, s.rejected_domain, s.retaken_at_kinks, s.newton_iterations,
             s.jacobians, s.lu_factorizations, s.events, s.time_events, s.jumps, output.newton_iterations,
             output.lu_factorizations, s.unsolved_points, output.unsolved_points, s.unresolved_steps, unknowns, t_end,
             wall);
}

// Points inside steps written or used from the polynomial (Statistics::unsolved_points): the
// waveform may be off there by more than the tolerance, which the user must know.
void warn_unsolved_points(const padae::Statistics& s, const padae::Statistics& output) {
  if (s.unsolved_points == 0 && output.unsolved_points == 0) return;
  fmt::print(stderr,
             "padsim: warning: Newton found no solution at {} output row(s) and {} event-location point(s) "
             "inside steps; the steps' interpolating polynomial stands in there, and its algebraic unknowns "
             "may be off by more than the tolerance\n",
             output.unsolved_points, s.unsolved_points);
}

// Steps accepted at the time resolution over a faster transient (Statistics::unresolved_steps):
// the state after it is right, its shape between the rows is not resolved.
void warn_unresolved_transients(const mna::Model& model, const padae::Statistics& s,
                                const std::optional<padae::UnresolvedTransient>& first) {
  if (s.unresolved_steps == 0 || !first) return;
  fmt::print(stderr,
             "padsim: warning: from t = {:.9g} s a transient faster than the time resolution ({:.3g} s there){} "
             "was passed over in {} step(s) at the minimum step, which backward Euler damps as it decays; "
             "its shape there is not resolved\n",
             first->t, first->resolution, blame(model, first->unknown), s.unresolved_steps);
}

// One run of the command, phase by phase; each phase returns an exit code (success: go on).
class Session {
 public:
  explicit Session(const CommandOptions& options) : options_(options) {}

  // Netlist, .tran, model, structural checks, columns. Errors: exit 2.
  int load() {
    netlist::Diagnostics diagnostics;
    std::optional<netlist::FlatCircuit> flat = netlist::load(options_.netlist, diagnostics);
    for (const auto& d : diagnostics.all())
      if (d.severity == netlist::Severity::error || !options_.quiet) fmt::print(stderr, "{}", netlist::format(d));
    if (!flat) return bad_input;
    if (!flat->tran && !options_.tstop) {
      print_error("the netlist has no .tran card (give --tstop)");
      return bad_input;
    }
    title_ = flat->title;
    inputs_ = {options_.netlist};
    for (const netlist::FlatElement& element : flat->elements)
      if (element.where.begin.file) inputs_.insert(element.where.begin.file->path);
    settings_.tstop = options_.tstop.value_or(flat->tran ? flat->tran->stop : 0);
    settings_.tstep = flat->tran && flat->tran->step > 0 ? flat->tran->step : settings_.tstop / 50;
    tstart_ = flat->tran ? flat->tran->start : 0;
    if (!(settings_.tstop > tstart_)) {
      print_error(fmt::format("the stop time {:g} s is not after the .tran start time {:g} s", settings_.tstop, tstart_));
      return bad_input;
    }
    // Far below any circuit's time scale, and where the integrator's time resolution (a few ulps
    // of the stop time) and the squares of its steps would underflow.
    constexpr double kShortestStopTime = 1e-100;
    if (settings_.tstop < kShortestStopTime) {
      print_error(fmt::format("the stop time {:g} s is below the shortest padsim simulates ({:g} s)", settings_.tstop,
                              kShortestStopTime));
      return bad_input;
    }
    uic_ = flat->tran && flat->tran->use_initial_conditions;
    mna::Tolerances tolerances;
    if (!apply_tolerances(*flat, options_, integrator_options_, tolerances)) return bad_input;
    if (!apply_method(*flat, options_, integrator_options_)) return bad_input;
    if (!check_temperature(*flat)) return bad_input;
    if (!options_.quiet) warn_of_unknown_options(*flat);
    settings_.reltol = integrator_options_.rtol;
    integrator_options_.time_scale = settings_.tstop;
    // TMAX, or (TSTOP - TSTART) / 50 as ngspice's fallback, and within a twentieth of any sine
    // source's period: the error test controls charges and fluxes only, so a quiet stretch could
    // otherwise step over source periods that guards and algebraic node voltages follow (not
    // TSTEP: that would give up the large steps).
    integrator_options_.max_step = flat->tran && flat->tran->max_step ? *flat->tran->max_step
                                                                      : (settings_.tstop - tstart_) / 50;
    try {
      model_ = std::make_unique<mna::Model>(mna::circuit_from_netlist(*flat), settings_);
      model_->set_tolerances(tolerances);
      integrator_options_.max_step = std::min(integrator_options_.max_step, model_->resolution_step());
      if (const std::string unresolved = unresolved_source_detail(*model_, integrator_options_, settings_.tstop);
          !unresolved.empty()) {
        print_error(unresolved);
        return bad_input;
      }
      mna::check_inductance_matrices(*model_);
      mna::check_structure(*model_, start_kind());
      if (!options_.probes.empty()) probes_ = parse_probes(options_.probes, *model_);
      else if (!flat->saves.empty()) probes_ = requested_probes(flat->saves, *model_);
      else probes_ = default_probes(*model_);
    } catch (const mna::ModelError& e) {
      if (const netlist::SourceRange* where = card_at_fault(*flat, e))
        fmt::print(stderr, "{}", netlist::format({netlist::Severity::error, *where, e.what()}));
      else
        print_error(e.what());
      return bad_input;
    }
    return success;
  }

  // Why an output may not be written, checked for all before any is opened (truncated), so that
  // a refusal loses nothing: an output that is an input (the netlist, a file it includes) or
  // another output, or that cannot be written. Empty when every output may be.
  std::string refused_output() const {
    namespace fs = std::filesystem;
    const std::pair<const char*, std::string> given[] = {
        {"-o", options_.output == "-" ? "" : options_.output},
        {"--raw", options_.raw},
        {"--events", options_.events},
        {"--plot", options_.plot}};
    std::vector<std::pair<const char*, std::string>> outputs;
    for (const auto& output : given)
      if (!output.second.empty()) outputs.push_back(output);
    // One file under two names (a link, ../): equivalent() when it exists, else the same
    // canonical path.
    auto same_file = [](const std::string& a, const std::string& b) {
      std::error_code error;
      if (fs::equivalent(a, b, error)) return true;
      const fs::path canonical_a = fs::weakly_canonical(a, error);
      if (error) return false;
      const fs::path canonical_b = fs::weakly_canonical(b, error);
      return !error && canonical_a == canonical_b;
    };
    for (std::size_t k = 0; k < outputs.size(); ++k) {
      const auto& [option, path] = outputs[k];
      for (const std::string& input : inputs_)
        if (same_file(path, input))
          return fmt::format("{} '{}' is the netlist's file '{}': refusing to write over it", option, path, input);
      for (std::size_t j = 0; j < k; ++j)
        if (same_file(path, outputs[j].second))
          return fmt::format("{} and {} name the same file '{}'", outputs[j].first, option, path);
      std::error_code error;
      if (fs::is_directory(path, error)) return fmt::format("cannot write {} '{}': it is a directory", option, path);
      const fs::path directory = fs::path(path).parent_path();
      const std::string must_write = fs::exists(path, error) ? path : directory.empty() ? "." : directory.string();
      if (::access(must_write.c_str(), W_OK) != 0)
        return fmt::format("cannot write {} '{}': {}", option, path, std::strerror(errno));
    }
    return "";
  }

  // CSV (stdout by default), raw file, event log; the plot reads a CSV file, so with the CSV on
  // stdout or on what cannot be read back (/dev/null, a pipe) a temporary one is written too.
  // Cannot open: exit 2.
  int open_outputs() {
    if (const std::string refused = refused_output(); !refused.empty()) {
      print_error(refused);
      return bad_input;
    }
    try {
      const std::string output = options_.output.empty() ? "-" : options_.output;
      plot_csv_ = output;
      std::error_code ignored;
      const auto kind = std::filesystem::status(output, ignored).type();
      const bool readable_back = output != "-" && (kind == std::filesystem::file_type::regular ||
                                                   kind == std::filesystem::file_type::not_found);
      if (!options_.plot.empty() && !readable_back) {
        temporary_csv_ = std::filesystem::temp_directory_path() / fmt::format("padsim-{}.csv", getpid());
        plot_csv_ = temporary_csv_.string();
        waveforms_.add(output::make_csv_writer(plot_csv_));
      }
      waveforms_.add(output::make_csv_writer(output));
      if (!options_.raw.empty()) waveforms_.add(output::make_raw_writer(options_.raw, !options_.raw_ascii, title_));
      if (!options_.events.empty()) event_log_ = output::make_event_writer(options_.events);
      waveforms_.begin(probes_);
    } catch (const std::exception& e) {
      print_error(e.what());
      return bad_input;
    }
    return success;
  }

  // Start, then step by step to TSTOP: every outcome becomes rows. A failure keeps the rows
  // written so far (exit 1); so does a writer failing mid-run (disk full).
  int simulate() {
    integrator_ = std::make_unique<padae::Integrator>(*model_, integrator_options_);
    progress_ = std::make_unique<Progress>(!options_.quiet, settings_.tstop);
    try {
      const mna::Start start = mna::find_start(*model_, 0, uic_, integrator_options_);
      // The modes the start is in: the operating point's, or (uic) the guards' at the initial
      // conditions, from which the initialization's fixed point may still reach a regular mode
      // (a current source's diodes turning on): checked when it does not.
      auto mode_structure_refused = [&]() {
        try {
          mna::check_mode_structure(*model_, start_kind(), start.p);
        } catch (const mna::ModelError& e) {
          print_error(e.what());
          return true;
        }
        return false;
      };
      if (!uic_ && mode_structure_refused()) return bad_input;
      // A start that fails on linear, singular equations is bad input (exit 2), named as such.
      auto singular = [&]() {
        const std::string why = mna::singular_linear_equations(*model_, start_kind(), start.p, 0, settings_.tstop);
        if (!why.empty()) print_error(why);
        return !why.empty();
      };
      if (!start.ok) {
        if (singular()) return bad_input;
        return fail(0, "no initial operating point: " + start.message, start.worst_unknown);
      }
      if (!integrator_->initialize(0, start.x, start.p)) {
        if ((uic_ && mode_structure_refused()) || singular()) return bad_input;
        return fail(integrator_->failure());
      }
      if (uic_ && !options_.quiet) warn_overridden_initial_conditions();
      emit(0, integrator_->state());

      while (integrator_->time() < settings_.tstop) {
        if (StopSignals::received()) return interrupted(integrator_->time());
        const double t_before = integrator_->time();
        const padae::StepOutcome outcome = integrator_->step(settings_.tstop);
        switch (outcome.kind) {
          case padae::StepKind::failed:
            return fail(integrator_->failure());
          case padae::StepKind::event: {
            if (!emit_inside(t_before, outcome)) return interrupted(last_row_);
            // Two rows at a discontinuity: the state just before and just after it.
            const padae::EventRecord& event = integrator_->last_event();
            if (waveforms_.differ(event.x_before, integrator_->state())) emit(outcome.t, event.x_before);
            emit(outcome.t, integrator_->state());
            if (event_log_) log_event(event);
            break;
          }
          case padae::StepKind::accepted:
          case padae::StepKind::time_event:
          case padae::StepKind::stop:
            if (!emit_inside(t_before, outcome)) return interrupted(last_row_);
            emit(outcome.t, integrator_->state());
            break;
        }
        progress_->update(outcome.t);
      }
    } catch (const output::WriteError& e) {
      return write_failed(e);
    } catch (const std::exception& e) {
      return fail(integrator_->time(), e.what(), -1);
    }
    return success;
  }

  // Flush the waveform, plot, statistics, temporary file. A failed plot makes exit 1 (the
  // waveform is complete, but not every requested output). A run that failed mid-way is plotted
  // up to where it stopped, which the plot's title says; one stopped by a signal is not.
  int finish(int status) {
    if (progress_) progress_->clear();
    status = close_outputs(status);
    const bool stopped = status == simulation_failure && !StopSignals::received();
    if (!options_.plot.empty() && StopSignals::received()) {
      // A signal asks padsim to end now; gnuplot could take long.
      fmt::print(stderr, "padsim: note: the plot '{}' is not written: the run was interrupted\n", options_.plot);
    } else if (!options_.plot.empty() && stopped && !wrote_rows_) {
      print_error(fmt::format("plot: '{}' not written: no rows were computed", options_.plot));
    } else if (!options_.plot.empty() && (status == success || stopped)) {
      const std::string note = stopped ? fmt::format("the run stopped at t = {:.9g} s", last_row_) : "";
      std::string error;
      if (!output::plot_png(plot_csv_, options_.plot, note, error)) {
        print_error("plot: " + error);
        status = simulation_failure;
      } else if (stopped) {
        fmt::print(stderr, "padsim: note: the plot '{}' shows the waveform up to t = {:.9g} s\n", options_.plot, last_row_);
      }
    }
    if (!temporary_csv_.empty()) std::filesystem::remove(temporary_csv_);
    if (!options_.quiet && integrator_) {
      warn_unsolved_points(integrator_->statistics(), integrator_->output_statistics());
      warn_unresolved_transients(*model_, integrator_->statistics(), integrator_->unresolved_transient());
    }
    if (options_.stats && integrator_)
      print_statistics(integrator_->statistics(), integrator_->output_statistics(), model_->size(),
                       integrator_->time(), wall_seconds());
    return status;
  }


 private:
  mna::StartKind start_kind() const {
    return uic_ ? mna::StartKind::initial_conditions : mna::StartKind::operating_point;
  }
  double wall_seconds() const { return std::chrono::duration<double>(Clock::now() - wall_start_).count(); }

  int fail(double t, const std::string& why, int unknown, const std::string& diagnosis = {}) {
    if (progress_) progress_->clear();
    print_error(fmt::format("simulation failed at t = {:.9g} s: {}{}{}", t, name_predicates(*model_, why),
                            blame(*model_, unknown), diagnosis.empty() ? "" : ": " + diagnosis));
    return simulation_failure;
  }
  // A run that stops at an event may have reached a mode the circuit's graph rules out: named.
  int fail(const padae::Failure& failure) {
    const std::string fault = failure.diagnosis.empty() ? mna::mode_structure_fault(*model_, integrator_->predicates()) : "";
    return fail(failure.t, failure.reason, failure.unknown, fault.empty() ? failure.diagnosis : "in the modes it stopped in: " + fault);
  }
  // uic starts from the initial conditions as given, and the consistent state at t = 0+ may
  // not keep them: a capacitor across a source, or capacitors in a loop whose ICs disagree,
  // take their charges at once (a jump). Said, since the netlist asked for other values.
  void warn_overridden_initial_conditions() const {
    for (const auto& ic : model_->overridden_initial_conditions(integrator_->state(), integrator_options_.rtol,
                                                                integrator_options_.atol)) {
      const char* unit = ic.current ? "A" : "V";
      fmt::print(stderr, "padsim: warning: uic: the initial condition of {} ({:.6g} {}) is {:.6g} {} at t = 0+: the circuit "
                 "overrides it\n", ic.name, ic.given, unit, ic.at_x, unit);
    }
  }
  // --events: a line per predicate flip, with the energy the whole event's jump dissipated.
  void log_event(const padae::EventRecord& event) {
    const double energy = event.jumped ? model_->jump_dissipation(event) : 0.0;
    for (const auto& flip : event.flips)
      event_log_->event(event.t, model_->predicate_owner(flip.predicate).name(), model_->predicate_label(flip.predicate),
                        int(flip.from), int(flip.to), energy);
  }
  // A file that could not be written (disk full, file-size limit) stops the run: said with where
  // the file now ends, its last whole row (or event), never a time past it.
  int write_failed(const output::WriteError& e) {
    if (progress_) progress_->clear();
    const char* record = e.path() == options_.events ? "event" : "row";
    std::string end = e.last_time() ? fmt::format("its last whole {} is at t = {} s", record, *e.last_time())
                                    : fmt::format("it holds no {}s", record);
    if (e.partial_tail()) end += ", and part of what followed it (it could not be cut back)";
    print_error(fmt::format("{}; {}", e.what(), end));
    if (e.path() == plot_csv_ && e.last_time()) last_row_ = *e.last_time();  // what the plot shows
    return simulation_failure;
  }
  // Flushes and closes every output. A writer that fails throws once and is then only closed,
  // so finishing again reaches the writers after it: each failure is reported.
  int close_outputs(int status) {
    for (;;) {
      try {
        waveforms_.finish();
        if (event_log_) event_log_->finish();
        return status;
      } catch (const output::WriteError& e) {
        status = write_failed(e);
      } catch (const std::exception& e) {
        print_error(e.what());
        status = simulation_failure;
      }
    }
  }
  void emit(double t, const mna::Vector& x) {
    if (t < tstart_) return;
    waveforms_.row(t, x);
    last_row_ = t;
    wrote_rows_ = true;
  }
  int interrupted(double t) {
    if (progress_) progress_->clear();
    const int signal = StopSignals::received();
    print_error(fmt::format("interrupted by {} at t = {:.9g} s; the waveform up to there is written",
                            signal == SIGTERM ? "SIGTERM" : signal == SIGINT ? "SIGINT" : "SIGHUP", t));
    return simulation_failure;
  }
  // Rows strictly inside the last step (also one that ended at an event), in time order, from
  // its dense output: at the source corners it passed (a corner that cannot bend the solution,
  // a gate drive's, does not end a step, but its waveform keeps the corner) and, with --grid, at
  // TSTART + k TSTEP. False where a stop signal came first (a TSTEP far below the steps makes
  // millions of rows in one step).
  bool emit_inside(double t_before, const padae::StepOutcome& outcome) {
    const double t_after = outcome.t;
    auto grid_point = [&](long k) {
      return options_.grid ? tstart_ + static_cast<double>(k) * settings_.tstep : mna::infinity;
    };
    // A source's jump at a corner the steps pass (it bends nothing with a state): the right
    // limit too, as an event's two rows, from the time resolution after it.
    auto emit_right_limit = [&](double corner) {
      const double right = std::min(corner + padae::time_resolution(corner, integrator_options_), t_after);
      emit(corner, integrator_->dense_output(right, waveforms_.unknowns_read()));
    };
    if (right_limit_due_ == t_before) emit_right_limit(t_before);
    right_limit_due_ = mna::infinity;
    while (grid_point(next_grid_) <= t_before) ++next_grid_;
    for (double corner = model_->next_time_event(t_before);;) {
      const double t_row = std::min(corner, grid_point(next_grid_));
      if (t_row >= t_after) {
        // A step that ended on a passable corner where a source jumps: its row is the left
        // limit, and the next step writes the right one. A time event's state is the right
        // limit already.
        if (corner == t_after && outcome.kind == padae::StepKind::accepted && model_->source_jumps_at(corner))
          right_limit_due_ = corner;
        return true;
      }
      if (StopSignals::received()) return false;
      emit(t_row, integrator_->dense_output(t_row, waveforms_.unknowns_read()));
      if (t_row == corner) {
        if (model_->source_jumps_at(corner)) emit_right_limit(corner);
        corner = model_->next_time_event(corner);
      }
      if (t_row == grid_point(next_grid_)) ++next_grid_;
    }
  }

  const CommandOptions& options_;
  const Clock::time_point wall_start_ = Clock::now();
  std::string title_;
  std::set<std::string> inputs_;  // the netlist and the files it includes
  mna::RunSettings settings_;
  double tstart_ = 0;
  bool uic_ = false;
  padae::Options integrator_options_;
  std::unique_ptr<mna::Model> model_;
  std::vector<Probe> probes_;
  Waveforms waveforms_;
  std::unique_ptr<output::EventWriter> event_log_;
  std::string plot_csv_;
  std::filesystem::path temporary_csv_;
  std::unique_ptr<padae::Integrator> integrator_;
  std::unique_ptr<Progress> progress_;
  long next_grid_ = 0;
  double right_limit_due_ = mna::infinity;  // the last step's end, where it wrote a jump's left limit
  double last_row_ = 0;  // the time of the last row written
  bool wrote_rows_ = false;
};

}  // namespace

std::optional<padae::Method> parse_method(const std::string& name) {
  if (name == "gear" || name == "bdf") return padae::Method::bdf;
  if (name == "trap" || name == "trapezoidal") return padae::Method::trapezoidal;
  return std::nullopt;
}

int run_command(const CommandOptions& options) {
  const StopSignals signals;
  // A file-size limit (ulimit -f) then fails the write with EFBIG, which is reported with where
  // the output ends, instead of killing padsim without a word.
  std::signal(SIGXFSZ, SIG_IGN);
  Session session(options);
  int status = session.load();
  if (status == success) status = session.open_outputs();
  if (status == success) status = session.finish(session.simulate());
  // A stop signal that came before the time loop (or during its last step) ends padsim too.
  if (const int signal = StopSignals::received()) StopSignals::die_of(signal);
  return status;
}

}  // namespace padsim
