// Waveform output of the padsim command: CSV, ngspice raw files, and a PNG plot via gnuplot; the
// event log.
//
// Writers stream: begin() once, row() per accepted time point, finish() at the end. Memory stays
// constant whatever the run length. Rows reach the file as whole lines (CSV) or whole points
// (raw) at least every 0.1 s of wall time, so a run killed mid-way leaves a readable file; the
// raw writer also keeps its "No. Points" field equal to the points on disk at every flush.
//
// Errors (cannot open, write failure) are reported as std::runtime_error carrying the path and
// the system's reason, write failures as WriteError. finish() may be called after such a failure,
// or twice: it then closes what is open and does not throw again.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace padsim::output {

// A write that failed (disk full, file-size limit). The records of the failed write are cut back
// off the file, so it ends at a whole record: the one of time last_time() (none: it holds no
// record). Where the file cannot be cut (a pipe), partial_tail() says that part of the failed
// write may follow it.
class WriteError : public std::runtime_error {
 public:
  WriteError(const std::string& message, std::string path, std::optional<double> last_time, bool partial_tail)
      : std::runtime_error(message), path_(std::move(path)), last_time_(last_time), partial_tail_(partial_tail) {}
  const std::string& path() const { return path_; }
  std::optional<double> last_time() const { return last_time_; }
  bool partial_tail() const { return partial_tail_; }

 private:
  std::string path_;
  std::optional<double> last_time_;
  bool partial_tail_;
};

class WaveformWriter {
 public:
  virtual ~WaveformWriter() = default;
  virtual void begin(const std::vector<std::string>& columns) = 0;  // names after "time", e.g. "v(out)", "i(l1)"
  virtual void row(double t, std::span<const double> values) = 0;   // streamed
  virtual void finish() = 0;                                        // flush and close; also safe after a failure
};

// CSV: header "time,<columns>", one line per row, every double in its shortest round-trip form
// (strtod gives back the identical bits). path "-" writes to standard output.
std::unique_ptr<WaveformWriter> make_csv_writer(const std::string& path);

// ngspice raw file ("Plotname: Transient Analysis", "Flags: real"), binary (little-endian doubles,
// point-major) or ascii ("Values:"). Variables named "i(...)" are typed current, all others voltage.
// Needs a seekable file (not "-"): the point count is patched in place.
std::unique_ptr<WaveformWriter> make_raw_writer(const std::string& path, bool binary, const std::string& title);

// --events: CSV "time,element,predicate,from,to,jump_energy", one line per predicate flip,
// streamed as the rows are (whole lines, at least every 0.1 s of wall time).
class EventWriter {
 public:
  virtual ~EventWriter() = default;
  virtual void event(double t, const std::string& element, const std::string& predicate, int from, int to,
                     double jump_energy) = 0;
  virtual void finish() = 0;  // flush and close; also safe after a failure
};
std::unique_ptr<EventWriter> make_event_writer(const std::string& path);

// Plots a CSV written by make_csv_writer into a PNG with gnuplot: time on x (scaled to s, ms, us
// or ns), one stacked panel per signal (signals grouped into a voltage and a current panel when
// there are more than six), titled with the CSV's name and the note, if any. Returns false and
// sets error when gnuplot is missing or fails.
bool plot_png(const std::string& csv_path, const std::string& png_path, const std::string& note, std::string& error);

}  // namespace padsim::output
