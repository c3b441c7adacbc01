// Engineering notation: suffixes, units, and what is not a number.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "netlist/netlist.hpp"

namespace {

struct NumberCase {
  const char* text;
  double value;
};

// Expected values are the doubles nearest to the decimal value (10u is 1e-5, not 10 * 1e-6).
const NumberCase numbers[] = {
    {"1", 1.0},         {"1.5", 1.5},        {".5", 0.5},        {"1e3", 1000.0},
    {"1E-3", 1e-3},     {"-2.5m", -2.5e-3},  {"+3", 3.0},        {"1f", 1e-15},
    {"1p", 1e-12},      {"1.5p", 1.5e-12},   {"3n", 3e-9},       {"1u", 1e-6},
    {"10uF", 1e-5},     {"1m", 1e-3},        {"1M", 1e-3},       {"1k", 1e3},
    {"1kOhm", 1e3},     {"1meg", 1e6},       {"1MEG", 1e6},      {"2.2meg", 2.2e6},
    {"1g", 1e9},        {"1t", 1e12},        {"1mil", 25.4e-6},  {"1Mil", 25.4e-6},
    {"10F", 1e-14},     {"5V", 5.0},         {"1e-3k", 1.0},     {"100nH", 1e-7},
    {"47uF", 47e-6},    {"1a", 1.0},         {"2.5Ohm", 2.5},    {"1Hz", 1.0},
    {"0.1u", 1e-7},     {"1.9u", 1.9e-6},    {"2.78us", 2.78e-6}, {"1.5e2k", 1.5e5},
};

TEST(Number, EngineeringSuffixes) {
  for (const NumberCase& c : numbers) {
    auto value = netlist::parse_number(c.text);
    ASSERT_TRUE(value.has_value()) << c.text;
    EXPECT_EQ(*value, c.value) << c.text;
  }
}

// Printing a double with the shortest representation and parsing it gives the same double.
TEST(Number, ShortestPrintoutRoundTrips) {
  for (double value : {1.0000000000000001e-07, 0.1 + 0.2, 1.0 / 3.0, 2.7799999999999996e-06,
                       6.02214076e23, 5e-324, 1.7976931348623157e308, 123456789.0})
    EXPECT_EQ(netlist::parse_number(fmt::format("{}", value)), value) << fmt::format("{}", value);
}

TEST(Number, RejectsNanInfAndGarbage) {
  for (const char* text : {"nan", "NaN", "inf", "Inf", "infinity", "-inf", "1k5", "k", "", "1..2",
                           "1e999", "--1", "1_0"})
    EXPECT_FALSE(netlist::parse_number(text).has_value()) << text;
}

}  // namespace
