// Malformed netlists: each gives exactly the expected first error, at the expected place.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <tuple>
#include <vector>

#include "netlist/netlist.hpp"

namespace {

struct Malformed {
  const char* text;  // the first line is the title
  int line, column;
  const char* message;
};

// Columns are 1-based and counted by hand from the card text.
const Malformed malformed[] = {
    // card syntax
    {"t\nR1 in\n", 2, 6, "expected a node name"},
    {"t\nR2 a b 1k 2k\n", 2, 11, "unexpected '2k'"},
    {"t\nQ1 c b e npn\n", 2, 1, "unknown element letter 'Q'"},
    {"t\n{R1 a b 1\n", 2, 1, "expected an element or a dot card"},
    {"t\n+ R1 a b 1\n", 2, 1, "continuation line '+' without a card to continue"},
    {"t\nR3 a b nan\n", 2, 8, "expected a value"},
    {"t\nR1 a b inf\n", 2, 8, "expected a value"},
    // beyond double's range either way: the same error (1e400 was "expected a value")
    {"t\nR1 a b 1e400\n", 2, 8, "number out of range"},
    {"t\nR1 a b 1e-400\n", 2, 8, "number out of range"},
    {"t\nR1 a b 2e306k\n", 2, 8, "number out of range"},  // 2e309 with the suffix
    {"t\nR4 a b 1k3\n", 2, 8, "expected a value"},
    {"t\nS1 a b c d\n", 2, 11, "expected a model name"},
    {"t\nW1 a b\n", 2, 7, "expected a voltage source name"},
    {"t\nK1 l1\n", 2, 6, "expected an inductor name"},
    {"t\nB1 a b x={1}\n", 2, 8, "expected V= or I="},
    {"t\nB1 a b v=\n", 2, 10, "expected an expression"},
    {"t\nX1\n", 2, 3, "expected a node name"},
    {"t\nV1 a 0 pulse(0 1\n", 2, 17, "expected ')'"},
    {"t\nV1 a 0 pulse(0)\n", 2, 8, "pulse takes 2 to 8 values, not 1"},
    {"t\nV1 a 0 pulse\n", 2, 13, "expected a value"},
    {"t\nV1 a 0 pulse 0\n", 2, 8, "pulse takes 2 to 8 values, not 1"},
    {"t\nV1 a 0 sin(0 1 2 3 4 5 6)\n", 2, 8, "sin takes 2 to 6 values, not 7"},
    {"t\nV1 a 0 sffm 0 1 2 3 4 5 6 7\n", 2, 8, "sffm takes 2 to 7 values, not 8"},
    {"t\nV1 a 0 pwl(0 0 1)\n", 2, 8, "pwl takes time-value pairs, not 3 values"},
    {"t\nV1 a 0 dc 1 2\n", 2, 13, "a second DC value for v1"},
    {"t\nE1 a 0 cur={1}\n", 2, 8, "an E source takes vol= or value=, not cur="},
    {"t\nG1 a 0 vol={1}\n", 2, 8, "a G source takes cur= or value=, not vol="},
    {"t\nG1 a 0 value=\n", 2, 14, "expected an expression"},
    {"t\nE1 a 0 poly(2) b 0 c 0\n", 2, 1, "poly(2) needs 4 control nodes and at least one coefficient"},
    {"t\nF1 a 0 poly(1) v1\n", 2, 1, "poly(1) needs 1 voltage source and at least one coefficient"},
    {"t\nE1 a 0 poly(1) b 0 1 x\n", 2, 22, "expected a poly coefficient, not 'x'"},
    {"t\nG1 a 0 poly(0) b 0 1\n", 2, 13, "poly() takes a whole number of controls from 1 to 16"},
    {"t\nE1 a 0 poly(1) (b 0 1\n", 2, 21, "expected ')'"},
    {"t\nV1 a 0 sin(0 1 1k) pulse(0 1)\n", 2, 20, "a second waveform for v1"},
    {"t\nV1 a 0 sin(0 1 1k) td=1\n", 2, 20, "unknown sin parameter 'td'"},
    // expressions
    {"t\nR1 a b {1+}\n", 2, 11, "expected an expression"},
    {"t\nR1 a b {(1+2}\n", 2, 13, "expected ')'"},
    {"t\nE1 a b c d {foo(1)}\n", 2, 13, "unknown function 'foo'"},
    {"t\nC1 a b {min(1)}\n", 2, 9, "function 'min' takes 2 arguments, not 1"},
    {"t\nB1 a b v={if(1,2)}\n", 2, 11, "function 'if' takes 3 arguments, not 2"},
    // dot cards
    {"t\n.tran 1n\n", 2, 9, "expected a value"},
    {"t\n.model d1 D(is=inf)\n", 2, 16, "expected a value"},
    {"t\n.ic v(a)\n", 2, 9, "expected '='"},
    {"t\n.param 1x=2\n", 2, 8, "expected name=value"},
    // Names expressions read as built-ins: ngspice 39 takes `.param time=5` (a B source's time is
    // still the simulation time, and R1 a 0 {time} a resistor of that time) and `.param pi=3`
    // (3 in an R value, 3.14159 in a B source); e, temper, hertz likewise.
    {"t\n.param a=1 time=5\n", 2, 12, "'time' is reserved (the simulation time) and cannot name a parameter"},
    {"t\n.param PI=3\n", 2, 8, "'pi' is reserved (the constant 3.14159...) and cannot name a parameter"},
    {"t\n.param e=7\n", 2, 8,
     "'e' is reserved (the constant 2.71828... in ngspice's B sources) and cannot name a parameter"},
    {"t\n.param temper=50\n", 2, 8, "'temper' is reserved (the circuit temperature in ngspice) and cannot name a parameter"},
    {"t\n.param hertz=1k\n", 2, 8, "'hertz' is reserved (the frequency of ngspice's AC analysis) and cannot name a parameter"},
    {"t\n.subckt s p params: pi=2\n.ends\n", 2, 21, "'pi' is reserved (the constant 3.14159...) and cannot name a parameter"},
    {"t\n.subckt s p\n.param time=1\n.ends\n", 3, 8, "'time' is reserved (the simulation time) and cannot name a parameter"},
    {"t\n.subckt s p w=1\n.ends\nX1 a s time=2\n", 4, 8, "'time' is reserved (the simulation time) and cannot name a parameter"},
    {"t\n.lib models.lib\n", 2, 16, "expected a library section name"},
    {"t\n.include nofile.cir\n", 2, 10, "cannot read 'nofile.cir': no such file"},
    {"t\nL1 a 0 1m ic=1 ic=2\n", 2, 16, "a second IC= for l1"},
    {"t\n.include /dev/null\n", 2, 10, "cannot read '/dev/null': not a regular file"},
    {"t\n.control\nrun\n", 2, 1, ".control without .endc"},
    {"t\n.subckt s a b\nR1 a b 1\n", 2, 9, "missing .ends for subcircuit 's'"},
    {"t\n.ends\n", 2, 1, ".ends without .subckt"},
    {"t\n.subckt s a b\nR1 a b 1\n.ends t\n", 4, 7, "'.ends t' closes subcircuit 's'"},
    // elaboration
    {"t\n.tran 0 1u\n", 2, 7, ".tran needs a positive time step"},
    {"t\n.tran 1n 0\n", 2, 10, ".tran needs a stop time after the start time"},
    {"t\n.tran 1n 1u 0 -1n\n", 2, 15, ".tran needs a positive maximum step"},
    {"t\n.ac dec 10 1 1k\n", 2, 1, ".ac is not supported: padsim runs transient analysis (.tran) only"},
    {"t\nD1 a b dmod\n", 2, 8, "model 'dmod' is not defined"},
    {"t\n.model sm sw(vt=1)\nD1 a b sm\n", 3, 8, "model 'sm' is a sw model; a diode needs a d model"},
    {"t\nF1 a b vx 2\n", 2, 8, "voltage source 'vx' is not defined"},
    {"t\nR9 a 0 1\nF1 a b r9 2\n", 3, 8, "'r9' is not a voltage source"},
    {"t\nB1 a 0 v={i(vy)}\n", 2, 11, "voltage source 'vy' is not defined"},
    {"t\nK1 l1 l2 0.5\n", 2, 4, "inductor 'l1' is not defined"},
    {"t\nX1 a b sub\n", 2, 8, "subcircuit 'sub' is not defined"},
    {"t\n.subckt sub p\nR1 p 0 1\n.ends\nX1 a b sub\n", 5, 1,
     "x1 connects 2 nodes; subcircuit 'sub' has 1 port"},
    {"t\n.subckt sub p\nR1 p 0 1\n.ends\nX1 a sub w=1\n", 5, 10,
     "subcircuit 'sub' has no parameter 'w'"},
    {"t\n.subckt loop p\nX1 p loop\n.ends\nX1 a loop\n", 3, 6, "subcircuit 'loop' instantiates itself"},
    // A port named twice was bound to the instance's last node of the two (ngspice: the first).
    {"t\n.subckt s2 a A\nR1 a 0 1\n.ends\nX2 vdd 0 s2\n", 2, 14, "port 'a' of subcircuit 's2' is named twice"},
    {"t\n.param a={b} b={a}\n", 2, 8, "parameter cycle: a -> b -> a"},
    {"t\nR1 a b {k}\n", 2, 9, "parameter 'k' is not defined"},
    {"t\nR1 a b 1\nR1 c d 2\n", 3, 1, "element 'r1' is defined twice"},
    {"t\nR1 a b {v(a)}\n", 2, 9, "a node voltage is only allowed in a B source expression"},
    {"t\nR1 a b {1/0}\n", 2, 9, "the value is not a finite number"},
    {"t\nR1 a b 1 m=2\n", 2, 10, "unknown parameter 'm' for resistor r1"},
    {"t\nD1 a 0 dm 2 area=3\n.model dm d\n", 2, 13, "diode d1: the area is given twice"},
    {"t\nV1 a 0 pwl(0 0 2 1 1 0)\n", 2, 20, "pwl times must not decrease"},
    {"t\nV1 a 0 pulse(0 1 0 1n 1n -1u 2u)\n", 2, 26, "pulse width must not be negative"},
    {"t\nV1 a 0 pulse(0 1 0 1n 1n 1u -2u)\n", 2, 29, "pulse period must not be negative"},
    {"t\nV1 a 0 pwl(0 0 1 1) r=0.5\n", 2, 23, "pwl r= must be one of the time points"},
};

// The first error of parsing and, if parsing succeeded, elaborating.
const netlist::Diagnostic* first_error(const std::string& text, netlist::Diagnostics& diagnostics) {
  netlist::ast::Netlist parsed = netlist::parse_text(text, "t.cir", diagnostics);
  if (!diagnostics.has_errors()) netlist::elaborate(parsed, diagnostics);
  const auto& all = diagnostics.all();
  auto error = std::find_if(all.begin(), all.end(), [](const netlist::Diagnostic& d) {
    return d.severity == netlist::Severity::error;
  });
  return error == all.end() ? nullptr : &*error;
}

TEST(Diagnostics, MalformedNetlists) {
  EXPECT_GE(std::size(malformed), 40u);
  for (const Malformed& m : malformed) {
    netlist::Diagnostics diagnostics;
    const netlist::Diagnostic* error = first_error(m.text, diagnostics);
    ASSERT_NE(error, nullptr) << m.text;
    EXPECT_EQ(error->message, m.message) << m.text;
    EXPECT_EQ(error->where.begin.line, m.line) << m.text;
    EXPECT_EQ(error->where.begin.column, m.column) << m.text;
    ASSERT_TRUE(error->where.begin.file) << m.text;
    EXPECT_EQ(error->where.begin.file->path, "t.cir") << m.text;
  }
}

TEST(Diagnostics, FormatNamesFileLineColumnWithCaret) {
  netlist::Diagnostics diagnostics;
  const netlist::Diagnostic* error = first_error("t\nR2 a b 1k 2k\n", diagnostics);
  ASSERT_NE(error, nullptr);
  EXPECT_EQ(netlist::format(*error),
            "t.cir:2:11: error: unexpected '2k'\n"
            "  R2 a b 1k 2k\n"
            "            ^~\n");
}

// What a diagnostic quotes or shows of the netlist is printable and short: control bytes were
// written to the terminal as they were (an escape sequence from a binary include), and a
// megabyte token three times (message, line, caret). A control byte in a name is refused: a NUL
// made a node "in\0" of its own, and went into the CSV header.
TEST(Diagnostics, QuotedAndShownTextIsPrintableAndShort) {
  using namespace std::string_literals;
  netlist::Diagnostics diagnostics;
  const netlist::Diagnostic* error = first_error("t\nR1 a b 1k \x01\x1b[31m\n"s, diagnostics);
  ASSERT_NE(error, nullptr);
  EXPECT_EQ(netlist::format(*error),
            "t.cir:2:11: error: unexpected '\\x01\\x1b[31m'\n"
            "  R1 a b 1k \\x01\\x1b[31m\n"
            "            ^~~~~~~~~~~~\n");

  netlist::Diagnostics long_token;
  error = first_error("t\nR1 a 0 1k " + std::string(1 << 20, 'x') + "\n", long_token);
  ASSERT_NE(error, nullptr);
  const std::string x60(netlist::kQuotedCharacters, 'x');
  EXPECT_EQ(error->message, "unexpected '" + x60 + "...'");
  const std::string shown = "R1 a 0 1k " + std::string(netlist::kShownCharacters - 10, 'x') + "...";
  EXPECT_EQ(netlist::format(*error), "t.cir:2:11: error: unexpected '" + x60 + "...'\n  " + shown + "\n  " +
                                         std::string(10, ' ') + "^" + std::string(netlist::kShownCharacters - 11, '~') + "\n");
  // An error far into a long line: the line from kShownBefore characters before it.
  netlist::Diagnostics far;
  error = first_error("t\nR1 " + std::string(1000, 'n') + " 0 {1+}\n", far);
  ASSERT_NE(error, nullptr);
  EXPECT_EQ(netlist::format(*error), "t.cir:2:1010: error: expected an expression\n  ..." +
                                         std::string(netlist::kShownBefore - 6, 'n') + " 0 {1+}\n     " +
                                         std::string(netlist::kShownBefore, ' ') + "^\n");

  netlist::Diagnostics nul;
  error = first_error("t\nV1 in 0 1\nR1 in\0 0 1k\n"s, nul);
  ASSERT_NE(error, nullptr);
  EXPECT_EQ(netlist::format(*error),
            "t.cir:3:6: error: the name 'in\\x00' contains a control character\n"
            "  R1 in\\x00 0 1k\n"
            "       ^~~~\n");
}

TEST(Diagnostics, CaretUnderContinuationLine) {
  netlist::Diagnostics diagnostics;
  const netlist::Diagnostic* error = first_error("t\nR1 a\n+  b nan\n", diagnostics);
  ASSERT_NE(error, nullptr);
  EXPECT_EQ(netlist::format(*error),
            "t.cir:3:6: error: expected a value\n"
            "  +  b nan\n"
            "       ^~~\n");
}

TEST(Diagnostics, SeveralErrorsInOnePass) {
  netlist::Diagnostics diagnostics;
  netlist::parse_text("t\nR1 in\nQ1 a b c npn\nR2 a b 1k\nC1 a b {1+}\nV1 a 0 pulse(0)\n", "t.cir",
                      diagnostics);
  std::vector<int> lines;
  for (const auto& d : diagnostics.all())
    if (d.severity == netlist::Severity::error) lines.push_back(d.where.begin.line);
  EXPECT_EQ(lines, (std::vector<int>{2, 3, 5, 6}));
}

TEST(Diagnostics, BrokenSubcktLineGivesNoFollowUpErrors) {
  netlist::Diagnostics diagnostics;
  netlist::parse_text("t\n.subckt\nR1 a b 1\n.ends\nR2 a b 1\n", "t.cir", diagnostics);
  ASSERT_EQ(diagnostics.error_count(), 1) << diagnostics.to_string();
  EXPECT_EQ(diagnostics.all()[0].message, "expected a subcircuit name");
  EXPECT_EQ(diagnostics.all()[0].where.begin.line, 2);
}

TEST(Diagnostics, SubcircuitErrorsAreReportedOncePerPlace) {
  netlist::Diagnostics diagnostics;
  auto parsed = netlist::parse_text(
      "t\n.subckt s a\nR1 a 0 {undefined}\n.ends\nX1 n1 s\nX2 n2 s\nX3 n3 s\n", "t.cir",
      diagnostics);
  EXPECT_FALSE(netlist::elaborate(parsed, diagnostics));
  ASSERT_EQ(diagnostics.error_count(), 1) << diagnostics.to_string();
  EXPECT_EQ(diagnostics.all()[0].message, "parameter 'undefined' is not defined");
  EXPECT_EQ(diagnostics.all()[0].where.begin.line, 3);
}

TEST(Diagnostics, DeepNestingIsAnErrorNotAStackOverflow) {
  // 100 parentheses reach the nesting limit of 200 (an expression and a unary level each); the
  // 101st '(' is at column 8 + 101.
  netlist::Diagnostics parens;
  first_error("t\nR1 a b {" + std::string(300, '(') + "1" + std::string(300, ')') + "}\n", parens);
  ASSERT_EQ(parens.error_count(), 1);
  EXPECT_EQ(parens.all()[0].message, "expression nested too deeply");
  EXPECT_EQ(parens.all()[0].where.begin.column, 109);
  // Each '-' is a unary level below the expression's: the 200th '-' (column 208) is too deep.
  netlist::Diagnostics minuses;
  first_error("t\nR1 a b {" + std::string(300, '-') + "1}\n", minuses);
  ASSERT_EQ(minuses.error_count(), 1);
  EXPECT_EQ(minuses.all()[0].message, "expression nested too deeply");
  EXPECT_EQ(minuses.all()[0].where.begin.column, 208);
  // A chain a + b + ... nests one level per operator: 10,000 terms overflowed the stack of the
  // walks that compile and evaluate it. The 1000th '+' (its operand at column 9 + 2 x 1000)
  // is one too many; 999 are fine.
  auto chain = [](int operators) {
    std::string text = "t\nR1 a b {1";
    for (int k = 0; k < operators; ++k) text += "+1";
    return text + "}\n";
  };
  netlist::Diagnostics long_chain;
  first_error(chain(10000), long_chain);
  ASSERT_EQ(long_chain.error_count(), 1);
  EXPECT_EQ(long_chain.all()[0].message,
            "expression too deep: more than 1000 operators in a chain (split it into parameters or sources)");
  EXPECT_EQ(long_chain.all()[0].where.begin.column, 2009);
  netlist::Diagnostics allowed;
  EXPECT_EQ(first_error(chain(999), allowed), nullptr) << allowed.to_string();
}

TEST(Diagnostics, IncludeCycleIsDetected) {
  netlist::Diagnostics diagnostics;
  std::string path = std::string(NETLIST_TEST_DATA) + "/invalid/cycle_a.cir";
  netlist::parse_file(path, diagnostics);
  ASSERT_EQ(diagnostics.error_count(), 1);
  const netlist::Diagnostic& error = diagnostics.all().front();
  EXPECT_EQ(error.where.begin.file->path, std::string(NETLIST_TEST_DATA) + "/invalid/cycle_b.inc");
  EXPECT_EQ(error.where.begin.line, 1);
  EXPECT_EQ(error.where.begin.column, 10);
  EXPECT_NE(error.message.find("include cycle: "), std::string::npos) << error.message;
  EXPECT_NE(error.message.find("cycle_a.cir -> "), std::string::npos) << error.message;
}

TEST(Diagnostics, HarmlessCardsWarnWithPosition) {
  netlist::Diagnostics diagnostics;
  auto circuit = netlist::load(std::string(NETLIST_TEST_DATA) + "/buck.cir", diagnostics);
  ASSERT_TRUE(circuit) << diagnostics.to_string();
  netlist::Diagnostics more;
  auto parsed = netlist::parse_text("t\nR1 a 0 1\n.tran 1n 1u\n.op\n.four 1k v(a)\n.frobnicate\n"
                                    ".model q1 npn(bf=100)\n.model d1 d(is=1e-14 zz=1)\n",
                                    "t.cir", more);
  auto flat = netlist::elaborate(parsed, more);
  ASSERT_TRUE(flat) << more.to_string();
  std::vector<std::pair<int, std::string>> warnings;
  for (const auto& d : flat->warnings) warnings.emplace_back(d.where.begin.line, d.message);
  std::sort(warnings.begin(), warnings.end());
  EXPECT_EQ(warnings, (std::vector<std::pair<int, std::string>>{
                          {4, ".op is ignored: padsim runs the transient analysis only"},
                          {5, ".four is ignored"},
                          {6, "unknown dot card '.frobnicate' is ignored"},
                          {7, "model type 'npn' is not supported by padsim; model 'q1' is ignored"},
                          {8, "unknown d model parameter 'zz' is kept but unused"},
                      }));
}

// A V or I source without a value was taken as DC 0 without a word; ngspice 39 says
// "Note: v1: has no value, DC 0 assumed", also when the card has only an AC magnitude. Once per
// card, however often its subcircuit is instantiated.
TEST(Diagnostics, SourceWithoutValueWarnsThatDcZeroIsAssumed) {
  netlist::Diagnostics diagnostics;
  auto parsed = netlist::parse_text("t\nV1 x 0\nI1 y 0 ac 1\nV2 z 0 dc 0\nI2 w 0 sin(0 1 1k)\nV3 u 0 0\n"
                                    ".subckt s p\n  V4 p 0\n.ends\nX1 a s\nX2 b s\n.tran 1n 1u\n",
                                    "t.cir", diagnostics);
  auto flat = netlist::elaborate(parsed, diagnostics);
  ASSERT_TRUE(flat) << diagnostics.to_string();
  std::vector<std::tuple<int, int, std::string>> warnings;
  for (const auto& d : flat->warnings) {
    EXPECT_EQ(d.severity, netlist::Severity::warning);
    warnings.emplace_back(d.where.begin.line, d.where.begin.column, d.message);
  }
  EXPECT_EQ(warnings, (std::vector<std::tuple<int, int, std::string>>{
                          {2, 1, "v1 has no value, DC 0 assumed"},
                          {3, 1, "i1 has no value, DC 0 assumed"},
                          {8, 3, "v4 has no value, DC 0 assumed"},
                      }));
  for (const char* name : {"v1", "i1", "x1.v4", "x2.v4"}) {
    const netlist::FlatElement* source = flat->find_element(name);
    ASSERT_NE(source, nullptr) << name;
    EXPECT_EQ(source->source.dc, 0.0) << name;
    EXPECT_FALSE(source->source.waveform) << name;
  }
  EXPECT_EQ(netlist::format(flat->warnings.front()),
            "t.cir:2:1: warning: v1 has no value, DC 0 assumed\n"
            "  V1 x 0\n"
            "  ^~\n");
}

}  // namespace
