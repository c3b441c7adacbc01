// CSV writer: "time,<columns>" then one line per row, doubles in shortest round-trip form.
#include <bit>
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
// Digits and zeros are moved in fixed-size blocks (one or two vector moves, where a copy of
// their exact length is a library call): a number may write this far past its own end.
constexpr std::size_t kBlock = 24;
constexpr std::size_t kOverrun = kBlock;

constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

constexpr std::uint64_t kPowersOfTen[] = {1ULL,
                                          10ULL,
                                          100ULL,
                                          1000ULL,
                                          10000ULL,
                                          100000ULL,
                                          1000000ULL,
                                          10000000ULL,
                                          100000000ULL,
                                          1000000000ULL,
                                          10000000000ULL,
                                          100000000000ULL,
                                          1000000000000ULL,
                                          10000000000000ULL,
                                          100000000000000ULL,
                                          1000000000000000ULL,
                                          10000000000000000ULL,
                                          100000000000000000ULL};

// The number of decimal digits of n > 0: log10 from the bit width (1233 / 4096 ~ log10 2),
// corrected by one comparison.
int digit_count(std::uint64_t n) {
  const int estimate = static_cast<int>((std::bit_width(n) * 1233) >> 12);
  return estimate + (n >= kPowersOfTen[estimate]);
}

// The eight decimal digits of n < 10^8, leading zeros included: 32-bit divisions by constants,
// where a loop of 64-bit ones by 100 cost twice the instructions.
void write_eight_digits(char* out, std::uint32_t n) {
  const std::uint32_t high = n / 10000, low = n % 10000;
  std::memcpy(out, kDigitPairs + 2 * (high / 100), 2);
  std::memcpy(out + 2, kDigitPairs + 2 * (high % 100), 2);
  std::memcpy(out + 4, kDigitPairs + 2 * (low / 100), 2);
  std::memcpy(out + 6, kDigitPairs + 2 * (low % 100), 2);
}

// v in fmt's "{}" form, character for character: the shortest digits that read back as v (fmt's
// Dragonbox), fixed notation for decimal exponents -4 ... 15, else d.ddde+XX. fmt's own layout
// of those digits took twice the instructions of the digits themselves: 9 % of a --grid run.
// Writes up to kOverrun bytes past the number's end.
char* write_shortest(char* out, double v) {
  if (!std::isfinite(v)) return fmt::format_to(out, FMT_COMPILE("{}"), v);
  if (std::signbit(v)) *out++ = '-', v = -v;
  if (v == 0) {
    *out++ = '0';
    return out;
  }
  const auto decimal = fmt::detail::dragonbox::to_decimal(v);  // significand * 10^exponent
  // A shortest significand has at most 17 digits: written right-aligned in 24, then read from
  // its first digit on in blocks of kBlock (the buffer's tail is slack).
  char buffer[24 + kBlock];
  std::uint64_t rest = decimal.significand;
  write_eight_digits(buffer + 16, static_cast<std::uint32_t>(rest % 100000000));
  rest /= 100000000;
  write_eight_digits(buffer + 8, static_cast<std::uint32_t>(rest % 100000000));
  buffer[7] = static_cast<char>('0' + rest / 100000000);
  const int count = digit_count(decimal.significand);
  const char* digits = buffer + 24 - count;
  const int leading = decimal.exponent + count - 1;  // the first digit's power of ten
  auto copy = [&out](const char* from, int n) {
    std::memcpy(out, from, kBlock);
    out += n;
  };
  auto zeros = [&out](int n) {
    std::memset(out, '0', kBlock);
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
    std::memcpy(out, kDigitPairs + 2 * magnitude, 2);
    out += 2;
  } else if (leading < 0) {  // 0.000ddd
    std::memcpy(out, "0.", 2);
    out += 2;
    zeros(-leading - 1);
    copy(digits, count);
  } else if (decimal.exponent >= 0) {  // an integer: ddd000 (at most 16 digits)
    copy(digits, count);
    zeros(decimal.exponent);
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
    out.resize(start + kMaxNumberLength * (values.size() + 1) + kOverrun);
    char* end = write_shortest(out.data() + start, t);
    for (double v : values) {
      *end++ = ',';
      end = write_shortest(end, v);
    }
    *end++ = '\n';
    out.resize(static_cast<std::size_t>(end - out.data()));
    sink_.commit(t);
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
