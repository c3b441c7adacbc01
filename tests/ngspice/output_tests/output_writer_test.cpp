// Tests of padsim_output: CSV round trip, raw files read back by ngspice, PNG plot.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include <fmt/format.h>

#include "cli/output/waveform_writer.hpp"

namespace fs = std::filesystem;
using padsim::output::make_csv_writer;
using padsim::output::make_raw_writer;
using padsim::output::plot_png;

namespace {

// A directory per test (and per process), so tests may run in parallel.
fs::path scratch(const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::temp_directory_path() /
                 (std::string("padsim-output-") + std::to_string(::getpid()) + "-" +
                  (info ? info->name() : "none"));
  fs::create_directories(dir);
  return dir / name;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::string line;
  std::istringstream in(text);
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out(1);
  for (char c : s) {
    if (c == sep) out.emplace_back();
    else out.back() += c;
  }
  return out;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Values that break naive formatting: non-terminating binary fractions, extremes, subnormals,
// negative zero, neighbours of round numbers; and what waveforms hold: grid times, integers,
// powers of ten at the edges of fixed notation.
std::vector<double> tricky_values() {
  std::vector<double> v = {0.1, 1.0 / 3.0, -2.0 / 3.0, M_PI, 1e-300, 5e-324, 2.2250738585072014e-308,
                           -0.0, 0.0, 1.7976931348623157e308, 1e23, 9007199254740993.0,
                           std::nextafter(1.0, 2.0), std::nextafter(1.0, 0.0), 123456789.123456789,
                           -1e-17, 4.35e-6};
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> mant(-1.0, 1.0);
  std::uniform_int_distribution<int> exp(-300, 300);
  for (int k = 0; k < 2000; ++k) v.push_back(std::ldexp(mant(rng), exp(rng)));
  for (int k = 0; k < 200; ++k) v.push_back(k * 1e-8);
  for (double p = 1e-7; p < 1e18; p *= 10) v.insert(v.end(), {p, -p, 1.5 * p, 123 * p});
  for (int k = 0; k < 200; ++k) {  // random bit patterns (finite only)
    std::uint64_t bits = rng();
    double d;
    std::memcpy(&d, &bits, sizeof d);
    if (std::isfinite(d)) v.push_back(d);
  }
  return v;
}

}  // namespace

TEST(CsvWriter, HeaderAndBitIdenticalRoundTrip) {
  auto path = scratch("roundtrip.csv");
  auto values = tricky_values();
  {
    auto w = make_csv_writer(path.string());
    w->begin({"v(out)", "i(l1)"});
    for (std::size_t k = 0; k + 1 < values.size(); k += 2) {
      double row[2] = {values[k], values[k + 1]};
      w->row(values[(k * 7) % values.size()], row);
    }
    w->finish();
  }
  auto lines = lines_of(slurp(path));
  ASSERT_EQ(lines.size(), 1 + values.size() / 2);
  EXPECT_EQ(lines[0], "time,v(out),i(l1)");
  // Each number reads back to the same bits, and is written as fmt writes "{}": its shortest
  // digits, in fixed notation for powers of ten -4 to 15.
  for (std::size_t r = 1; r < lines.size(); ++r) {
    std::size_t k = 2 * (r - 1);
    auto fields = split(lines[r], ',');
    ASSERT_EQ(fields.size(), 3u) << lines[r];
    double expect[3] = {values[(k * 7) % values.size()], values[k], values[k + 1]};
    for (int c = 0; c < 3; ++c) {
      char* end = nullptr;
      double got = std::strtod(fields[c].c_str(), &end);
      EXPECT_EQ(*end, '\0') << fields[c];
      EXPECT_TRUE(same_bits(got, expect[c])) << fields[c] << " vs " << expect[c];
      EXPECT_EQ(fields[c], fmt::format("{}", expect[c]));
    }
  }
}

TEST(CsvWriter, NonFiniteValuesParseBack) {
  auto path = scratch("nonfinite.csv");
  auto w = make_csv_writer(path.string());
  w->begin({"a", "b", "c"});
  double row[3] = {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN()};
  w->row(0.5, row);
  w->finish();
  auto lines = lines_of(slurp(path));
  ASSERT_EQ(lines.size(), 2u);
  auto f = split(lines[1], ',');
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(std::strtod(f[1].c_str(), nullptr), std::numeric_limits<double>::infinity());
  EXPECT_EQ(std::strtod(f[2].c_str(), nullptr), -std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(std::strtod(f[3].c_str(), nullptr)));
}

TEST(CsvWriter, QuotesNamesWithCommas) {
  auto path = scratch("names.csv");
  auto w = make_csv_writer(path.string());
  w->begin({"v(a,b)", "x\"y"});
  w->finish();
  EXPECT_EQ(lines_of(slurp(path)).at(0), "time,\"v(a,b)\",\"x\"\"y\"");
}

// A run that is killed leaves whole lines on disk, and rows reach the disk within ~0.1 s.
TEST(CsvWriter, StreamsWholeLinesBeforeFinish) {
  auto path = scratch("stream.csv");
  auto w = make_csv_writer(path.string());
  w->begin({"v(x)"});
  EXPECT_EQ(slurp(path), "time,v(x)\n");  // header on disk at once
  // Many rows: the size limit forces flushes; the file must always end with a newline.
  for (int k = 0; k < 200000; ++k) {
    double v = std::sin(k * 1e-3);
    w->row(k * 1e-6, std::span<const double>(&v, 1));
    if (k % 20000 == 0) {
      auto text = slurp(path);
      ASSERT_FALSE(text.empty());
      EXPECT_EQ(text.back(), '\n') << "after row " << k;
    }
  }
  auto before = slurp(path);
  EXPECT_GT(lines_of(before).size(), 100000u);
  // Slow producer: rows arrive every 5 ms; they must be on disk within about 0.1 s.
  auto slow = scratch("slow.csv");
  auto s = make_csv_writer(slow.string());
  s->begin({"v(x)"});
  for (int k = 0; k < 60; ++k) {
    double v = k;
    s->row(k, std::span<const double>(&v, 1));
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  auto partial = slurp(slow);
  EXPECT_GT(lines_of(partial).size(), 40u) << "rows older than 0.1 s are still in memory";
  EXPECT_EQ(partial.back(), '\n');
  // A row that comes 0.1 s or more after the previous flush is written at once.
  std::this_thread::sleep_for(std::chrono::milliseconds(120));
  double late = 99;
  s->row(99, std::span<const double>(&late, 1));
  EXPECT_EQ(lines_of(slurp(slow)).back(), "99,99");
  s->finish();
  EXPECT_EQ(lines_of(slurp(slow)).size(), 62u);
  w->finish();
  EXPECT_EQ(lines_of(slurp(path)).size(), 200001u);
}

TEST(CsvWriter, FailuresThrowAndFinishStaysSafe) {
  EXPECT_THROW(make_csv_writer("/nonexistent-dir/x/y.csv"), std::runtime_error);
  if (fs::exists("/dev/full")) {
    auto w = make_csv_writer("/dev/full");
    bool threw = false;
    try {
      w->begin({"v(a)"});
      for (int k = 0; k < 100000; ++k) {
        double v = k;
        w->row(k, std::span<const double>(&v, 1));
      }
      w->finish();
    } catch (const std::runtime_error& e) {
      threw = true;
      EXPECT_NE(std::string(e.what()).find("/dev/full"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(threw);
    EXPECT_NO_THROW(w->finish());
    EXPECT_NO_THROW(w->finish());
  }
  auto w = make_csv_writer(scratch("twice.csv").string());
  w->begin({"a"});
  double v = 1;
  EXPECT_THROW(w->row(0, std::span<const double>()), std::invalid_argument);
  w->row(0, std::span<const double>(&v, 1));
  w->finish();
  EXPECT_NO_THROW(w->finish());
}

// ---------------------------------------------------------------------------------------------
// Raw files, read back by ngspice.

namespace {

struct Signals {
  std::vector<double> t, v, i;
};

Signals test_signals(int n) {
  Signals s;
  double t = 0;
  for (int k = 0; k < n; ++k) {
    s.t.push_back(t);
    s.v.push_back(5.0 * std::sin(2 * M_PI * 1e3 * t) + 1.0 / 3.0);
    s.i.push_back(-1e-3 * std::exp(-t / 2e-4) + 1e-9 * k);
    t += 1e-6 * (1.0 + 0.5 * std::sin(k));  // non-uniform steps, like an adaptive integrator
  }
  return s;
}

void write_raw(const fs::path& path, bool binary, const Signals& s) {
  auto w = make_raw_writer(path.string(), binary, "padsim output test");
  w->begin({"v(out)", "i(l1)"});
  for (std::size_t k = 0; k < s.t.size(); ++k) {
    double row[2] = {s.v[k], s.i[k]};
    w->row(s.t[k], row);
  }
  w->finish();
}

// Runs ngspice on a deck that loads the raw file and writes its vectors with wrdata.
// Returns the rows of numbers (time, v(out), i(l1)).
std::vector<std::vector<double>> ngspice_reads(const fs::path& raw, std::string& log) {
  fs::path deck = raw.parent_path() / (raw.stem().string() + "-load.cir");
  fs::path data = raw.parent_path() / (raw.stem().string() + "-data.txt");
  fs::path out = raw.parent_path() / (raw.stem().string() + "-ngspice.log");
  {
    std::ofstream d(deck);
    d << "* load a padsim raw file\n.control\nset wr_singlescale\nset wr_vecnames\n"
         "option numdgt=17\nload " << raw.string() << "\n"
      << "wrdata " << data.string() << " v(out) i(l1)\n"
      << "print length(time) > " << (raw.parent_path() / "len.txt").string() << "\n"
      << "quit\n.endc\n.end\n";
  }
  std::string cmd = std::string(PADSIM_NGSPICE) + " -b " + deck.string() + " > " + out.string() + " 2>&1";
  int rc = std::system(cmd.c_str());
  log = slurp(out);
  EXPECT_EQ(rc, 0) << log;
  std::vector<std::vector<double>> rows;
  auto lines = lines_of(slurp(data));
  for (std::size_t k = 1; k < lines.size(); ++k) {  // line 0: the vector names
    std::istringstream in(lines[k]);
    std::vector<double> row;
    double x;
    while (in >> x) row.push_back(x);
    if (!row.empty()) rows.push_back(row);
  }
  return rows;
}

void expect_ngspice_reads_back(bool binary) {
  ASSERT_TRUE(std::string(PADSIM_NGSPICE).size() > 0) << "ngspice not found at configure time";
  auto path = scratch(binary ? "binary.raw" : "ascii.raw");
  auto s = test_signals(1500);
  write_raw(path, binary, s);
  std::string log;
  auto rows = ngspice_reads(path, log);
  ASSERT_EQ(rows.size(), s.t.size()) << log;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    ASSERT_EQ(rows[k].size(), 3u);
    const double want[3] = {s.t[k], s.v[k], s.i[k]};
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(rows[k][c], want[c], 1e-14 * std::max(1.0, std::fabs(want[c])) + 1e-300)
          << "row " << k << " column " << c;
  }
  EXPECT_EQ(log.find("rror"), std::string::npos) << log;
}

}  // namespace

TEST(RawWriter, BinaryReadBackByNgspice) { expect_ngspice_reads_back(true); }
TEST(RawWriter, AsciiReadBackByNgspice) { expect_ngspice_reads_back(false); }

TEST(RawWriter, HeaderFields) {
  auto path = scratch("header.raw");
  write_raw(path, false, test_signals(3));
  auto lines = lines_of(slurp(path));
  ASSERT_GT(lines.size(), 11u);
  EXPECT_EQ(lines[0], "Title: padsim output test");
  EXPECT_EQ(lines[2], "Plotname: Transient Analysis");
  EXPECT_EQ(lines[3], "Flags: real");
  EXPECT_EQ(lines[4], "No. Variables: 3");
  EXPECT_EQ(lines[5].rfind("No. Points: 3 ", 0), 0u) << lines[5];
  EXPECT_EQ(lines[6], "Variables:");
  EXPECT_EQ(lines[7], "\t0\ttime\ttime");
  EXPECT_EQ(lines[8], "\t1\tv(out)\tvoltage");
  EXPECT_EQ(lines[9], "\t2\ti(l1)\tcurrent");
  EXPECT_EQ(lines[10], "Values:");
  EXPECT_THROW(make_raw_writer("-", true, "x"), std::invalid_argument);
}

// Before finish(), the point count on disk matches the points on disk (a killed run is readable).
TEST(RawWriter, PointCountFollowsFlushes) {
  auto path = scratch("partial.raw");
  auto w = make_raw_writer(path.string(), true, "partial");
  w->begin({"v(a)"});
  for (int k = 0; k < 100000; ++k) {
    double v = k;
    w->row(k * 1e-9, std::span<const double>(&v, 1));
  }
  auto text = slurp(path);
  auto header_end = text.find("Binary:\n");
  ASSERT_NE(header_end, std::string::npos);
  std::size_t data_bytes = text.size() - (header_end + 8);
  EXPECT_EQ(data_bytes % 16, 0u);
  auto count_at = text.find("No. Points: ");
  std::size_t count = std::strtoull(text.c_str() + count_at + 12, nullptr, 10);
  EXPECT_GT(count, 0u);
  EXPECT_EQ(count, data_bytes / 16);
  w->finish();
  text = slurp(path);
  EXPECT_EQ(std::strtoull(text.c_str() + text.find("No. Points: ") + 12, nullptr, 10), 100000u);
}

// ---------------------------------------------------------------------------------------------

TEST(PlotPng, WritesAPng) {
  auto csv = scratch("plot.csv");
  auto png = scratch("plot.png");
  auto s = test_signals(400);
  {
    auto w = make_csv_writer(csv.string());
    w->begin({"v(out)", "i(l1)", "v(sw_node)"});
    for (std::size_t k = 0; k < s.t.size(); ++k) {
      double row[3] = {s.v[k], s.i[k], s.v[k] > 0 ? 12.0 : 0.0};
      w->row(s.t[k], row);
    }
    w->finish();
  }
  std::string error;
  ASSERT_TRUE(plot_png(csv.string(), png.string(), "", error)) << error;
  auto bytes = slurp(png);
  ASSERT_GT(bytes.size(), 2000u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  if (const char* keep = std::getenv("PADSIM_KEEP_PLOT")) fs::copy_file(png, keep, fs::copy_options::overwrite_existing);
}

TEST(PlotPng, ReportsErrors) {
  std::string error;
  EXPECT_FALSE(plot_png("/nonexistent/x.csv", scratch("x.png").string(), "", error));
  EXPECT_NE(error.find("/nonexistent/x.csv"), std::string::npos);
  auto empty = scratch("empty.csv");
  std::ofstream(empty) << "time,v(a)\n";
  error.clear();
  EXPECT_FALSE(plot_png(empty.string(), scratch("y.png").string(), "", error));
  EXPECT_FALSE(error.empty());
}
