// ngspice raw file writer. The header's "No. Points" field is a fixed-width placeholder that is
// rewritten in place after every flush and in finish(), so the file on disk is always a valid raw
// file holding the points written so far.
#include <bit>
#include <cstring>
#include <ctime>
#include <iterator>
#include <stdexcept>

#include <fmt/format.h>

#include "cli/output/waveform_writer.hpp"
#include "file_sink.hpp"

namespace padsim::output {

namespace {

// Appends formatted text to a buffer.
template <typename Buffer, typename... Args>
void put(Buffer& out, fmt::format_string<Args...> format, Args&&... args) {
  fmt::format_to(std::back_inserter(out), format, std::forward<Args>(args)...);
}

constexpr int count_width = 20;  // digits reserved for the point count

std::string variable_type(const std::string& name) {
  if (name.size() > 2 && (name[0] == 'i' || name[0] == 'I') && name[1] == '(') return "current";
  return "voltage";
}

class RawWriter final : public WaveformWriter {
 public:
  RawWriter(const std::string& path, bool binary, std::string title)
      : sink_(checked(path)), binary_(binary), title_(std::move(title)) {
    static_assert(std::endian::native == std::endian::little, "raw files are little-endian");
  }

  void begin(const std::vector<std::string>& columns) override {
    if (begun_) throw std::logic_error("RawWriter::begin called twice");
    begun_ = true;
    columns_ = columns.size();
    auto& out = sink_.buffer();
    std::string title = title_;
    for (char& c : title)
      if (c == '\n' || c == '\r') c = ' ';
    char date[64] = "";
    std::time_t now = std::time(nullptr);
    std::tm tm{};
    if (localtime_r(&now, &tm)) std::strftime(date, sizeof date, "%a %b %d %H:%M:%S  %Y", &tm);
    put(out, "Title: {}\n", title);
    put(out, "Date: {}\n", date);
    put(out, "Plotname: Transient Analysis\n");
    put(out, "Flags: real\n");
    put(out, "No. Variables: {}\n", columns.size() + 1);
    put(out, "No. Points: ");
    count_offset_ = static_cast<std::int64_t>(out.size());
    put(out, "{:<{}}\n", 0, count_width);
    put(out, "Variables:\n");
    put(out, "\t0\ttime\ttime\n");
    for (std::size_t k = 0; k < columns.size(); ++k)
      put(out, "\t{}\t{}\t{}\n", k + 1, columns[k], variable_type(columns[k]));
    put(out, "{}", binary_ ? "Binary:\n" : "Values:\n");
    sink_.flush();
  }

  void row(double t, std::span<const double> values) override {
    if (!begun_) throw std::logic_error("RawWriter::row before begin");
    if (values.size() != columns_)
      throw std::invalid_argument(
          fmt::format("RawWriter::row: {} values for {} columns", values.size(), columns_));
    auto& out = sink_.buffer();
    if (binary_) {
      auto put_double = [&](double v) {
        char bytes[sizeof(double)];
        std::memcpy(bytes, &v, sizeof v);
        out.append(bytes, bytes + sizeof bytes);
      };
      put_double(t);
      for (double v : values) put_double(v);
    } else {
      fmt::format_to(std::back_inserter(out), " {}\t{:.17e}\n", points_, t);
      for (double v : values) fmt::format_to(std::back_inserter(out), "\t{:.17e}\n", v);
      out.push_back('\n');
    }
    ++points_;
    if (sink_.commit(t)) patch_count(points_);
  }

  void finish() override {
    if (done_) return;
    done_ = true;
    if (sink_.failed() || !begun_) {
      sink_.close();
      return;
    }
    sink_.flush();
    patch_count(points_);
    sink_.close();
  }

 private:
  static const std::string& checked(const std::string& path) {
    if (path == "-") throw std::invalid_argument("raw output needs a file, not standard output");
    return path;
  }
  void patch_count(std::size_t points) {
    sink_.pwrite_at(count_offset_, fmt::format("{:<{}}", points, count_width));
  }

  detail::FileSink sink_;
  bool binary_;
  std::string title_;
  std::size_t columns_ = 0;
  std::size_t points_ = 0;
  std::int64_t count_offset_ = 0;
  bool begun_ = false;
  bool done_ = false;
};

}  // namespace

std::unique_ptr<WaveformWriter> make_raw_writer(const std::string& path, bool binary,
                                                const std::string& title) {
  return std::make_unique<RawWriter>(path, binary, title);
}

}  // namespace padsim::output
