// CSV writer: "time,<columns>" then one line per row, doubles in shortest round-trip form.
#include <cmath>
#include <cstdint>
#include <cstring>
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

constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// The decimal digits of n, written to end just before `end`; returns where they begin.
char* digits_before(char* end, std::uint64_t n) {
  for (; n >= 100; n /= 100) {
    end -= 2;
    std::memcpy(end, kDigitPairs + 2 * (n % 100), 2);
  }
  if (n >= 10) {
    end -= 2;
    std::memcpy(end, kDigitPairs + 2 * n, 2);
  } else {
    *--end = static_cast<char>('0' + n);
  }
  return end;
}

// v in fmt's "{}" form, character for character: the shortest digits that read back as v (fmt's
// Dragonbox), fixed notation for decimal exponents -4 ... 15, else d.ddde+XX. fmt's own layout
// of those digits took twice the instructions of the digits themselves: 9 % of a --grid run.
char* write_shortest(char* out, double v) {
  if (!std::isfinite(v)) return fmt::format_to(out, FMT_COMPILE("{}"), v);
  if (std::signbit(v)) *out++ = '-', v = -v;
  if (v == 0) {
    *out++ = '0';
    return out;
  }
  const auto decimal = fmt::detail::dragonbox::to_decimal(v);  // significand * 10^exponent
  char buffer[20];
  char* const digits_end = buffer + sizeof buffer;
  const char* digits = digits_before(digits_end, decimal.significand);
  const int count = static_cast<int>(digits_end - digits);
  const int leading = decimal.exponent + count - 1;  // the first digit's power of ten
  auto copy = [&out](const char* from, int n) {
    std::memcpy(out, from, static_cast<std::size_t>(n));
    out += n;
  };
  auto fill = [&out](char c, int n) {
    std::memset(out, c, static_cast<std::size_t>(n));
    out += n;
  };
  if (leading < -4 || leading >= 16) {
    *out++ = digits[0];
    if (count > 1) {
      *out++ = '.';
      copy(digits + 1, count - 1);
    }
    *out++ = 'e';
    *out++ = leading < 0 ? '-' : '+';
    int magnitude = std::abs(leading);
    if (magnitude >= 100) *out++ = static_cast<char>('0' + magnitude / 100), magnitude %= 100;
    copy(kDigitPairs + 2 * magnitude, 2);
  } else if (leading < 0) {  // 0.000ddd
    copy("0.", 2);
    fill('0', -leading - 1);
    copy(digits, count);
  } else if (decimal.exponent >= 0) {  // an integer: ddd000
    copy(digits, count);
    fill('0', decimal.exponent);
  } else {  // ddd.ddd
    copy(digits, leading + 1);
    *out++ = '.';
    copy(digits + leading + 1, count - leading - 1);
  }
  return out;
}

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
    // Formatted into room made for the whole line: written through a pointer, without a
    // capacity check per character.
    const std::size_t start = out.size();
    out.resize(start + kMaxNumberLength * (values.size() + 1));
    char* end = write_shortest(out.data() + start, t);
    for (double v : values) {
      *end++ = ',';
      end = write_shortest(end, v);
    }
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
