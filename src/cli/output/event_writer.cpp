// Event log writer: "time,element,predicate,from,to,jump_energy", one line per predicate flip.
#include <iterator>

#include <fmt/format.h>

#include "cli/output/waveform_writer.hpp"
#include "file_sink.hpp"

namespace padsim::output {

namespace {

// RFC 4180: a label with a comma or a quote ("v(a,b)>0") is quoted, its quotes doubled.
std::string field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

class CsvEventWriter final : public EventWriter {
 public:
  explicit CsvEventWriter(const std::string& path) : sink_(path) {
    fmt::format_to(std::back_inserter(sink_.buffer()), "time,element,predicate,from,to,jump_energy\n");
    sink_.flush();  // the header is on disk at once
  }
  void event(double t, const std::string& element, const std::string& predicate, int from, int to,
             double jump_energy) override {
    fmt::format_to(std::back_inserter(sink_.buffer()), "{},{},{},{},{},{}\n", t, field(element), field(predicate), from,
                   to, jump_energy);
    sink_.commit(t);
  }
  void finish() override { sink_.close(); }

 private:
  detail::FileSink sink_;
};

}  // namespace

std::unique_ptr<EventWriter> make_event_writer(const std::string& path) {
  return std::make_unique<CsvEventWriter>(path);
}

}  // namespace padsim::output
