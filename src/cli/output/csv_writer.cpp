// CSV writer: "time,<columns>" then one line per row, doubles in shortest round-trip form.
#include <iterator>
#include <stdexcept>

#include <fmt/compile.h>
#include <fmt/format.h>

#include "cli/output/waveform_writer.hpp"
#include "file_sink.hpp"

namespace padsim::output {

namespace {

// The longest double in shortest round-trip form, "-2.2250738585072014e-308" (24), and a comma.
constexpr std::size_t kMaxNumberLength = 25;

class CsvWriter final : public WaveformWriter {
 public:
  explicit CsvWriter(const std::string& path) : sink_(path) {}

  void begin(const std::vector<std::string>& columns) override {
    if (begun_) throw std::logic_error("CsvWriter::begin called twice");
    begun_ = true;
    columns_ = columns.size();
    auto& out = sink_.buffer();
    fmt::format_to(std::back_inserter(out), "time");
    for (const auto& name : columns) {
      // A name with a comma or a quote is quoted (RFC 4180); probe names normally have neither.
      if (name.find_first_of(",\"\n") != std::string::npos) {
        out.push_back(',');
        out.push_back('"');
        for (char c : name) {
          if (c == '"') out.push_back('"');
          out.push_back(c);
        }
        out.push_back('"');
      } else {
        fmt::format_to(std::back_inserter(out), ",{}", name);
      }
    }
    out.push_back('\n');
    sink_.flush();  // the header is on disk at once
  }

  void row(double t, std::span<const double> values) override {
    if (!begun_) throw std::logic_error("CsvWriter::row before begin");
    if (values.size() != columns_)
      throw std::invalid_argument(
          fmt::format("CsvWriter::row: {} values for {} columns", values.size(), columns_));
    auto& out = sink_.buffer();
    // Formatted into room made for the whole line: through a pointer fmt writes each character
    // without the appending's capacity check, and its format string is compiled (parsing it at
    // run time took more than the conversions).
    const std::size_t start = out.size();
    out.resize(start + kMaxNumberLength * (values.size() + 1));
    char* end = fmt::format_to(out.data() + start, FMT_COMPILE("{}"), t);
    for (double v : values) end = fmt::format_to(end, FMT_COMPILE(",{}"), v);
    *end++ = '\n';
    out.resize(static_cast<std::size_t>(end - out.data()));
    sink_.commit();
  }

  void finish() override { sink_.close(); }

 private:
  detail::FileSink sink_;
  std::size_t columns_ = 0;
  bool begun_ = false;
};

}  // namespace

std::unique_ptr<WaveformWriter> make_csv_writer(const std::string& path) {
  return std::make_unique<CsvWriter>(path);
}

}  // namespace padsim::output
