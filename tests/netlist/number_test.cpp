// Engineering notation: suffixes, units, and what is not a number.
#include <gtest/gtest.h>

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
};

TEST(Number, EngineeringSuffixes) {
  for (const NumberCase& c : numbers) {
    auto value = netlist::parse_number(c.text);
    ASSERT_TRUE(value.has_value()) << c.text;
    EXPECT_EQ(*value, c.value) << c.text;
  }
}

TEST(Number, RejectsNanInfAndGarbage) {
  for (const char* text : {"nan", "NaN", "inf", "Inf", "infinity", "-inf", "1k5", "k", "", "1..2",
                           "1e999", "--1", "1_0"})
    EXPECT_FALSE(netlist::parse_number(text).has_value()) << text;
}

}  // namespace
