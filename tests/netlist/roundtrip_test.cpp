// The AST printer round-trips: printing and parsing again gives the same AST. The printer
// writes every field of every card, so equal printouts mean equal ASTs (positions aside).
#include <gtest/gtest.h>

#include <filesystem>

#include "netlist/netlist.hpp"

namespace {

void expect_round_trip(const std::string& text, const std::string& path) {
  netlist::Diagnostics diagnostics;
  auto first = netlist::parse_text(text, path, diagnostics);
  ASSERT_FALSE(diagnostics.has_errors()) << diagnostics.to_string();
  std::string printed = netlist::print(first);
  auto second = netlist::parse_text(printed, path, diagnostics);
  ASSERT_FALSE(diagnostics.has_errors()) << printed << diagnostics.to_string();
  EXPECT_EQ(netlist::print(second), printed);
  EXPECT_EQ(second.cards.size(), first.cards.size());
}

TEST(RoundTrip, EveryTestNetlist) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(NETLIST_TEST_DATA)) {
    if (entry.path().extension() != ".cir") continue;
    netlist::Diagnostics diagnostics;
    auto parsed = netlist::parse_file(entry.path(), diagnostics);
    std::string printed = netlist::print(parsed);
    SCOPED_TRACE(entry.path().string());
    expect_round_trip(printed, entry.path().string());
    ++count;
  }
  EXPECT_GE(count, 6);
}

// A lone '$' starts an inline comment, so it cannot be a name (found by the fuzzer: ".subckt$ outer"
// took "$" as the subcircuit's name, and the printed ".subckt $ outer" lost it to a comment). A
// '$' inside or at the start of a longer name is kept.
TEST(RoundTrip, ALoneDollarIsNoName) {
  netlist::Diagnostics diagnostics;
  netlist::parse_text("t\n.subckt$ outer x y\nR1 x y 1\n.ends\n", "dollar.cir", diagnostics);
  EXPECT_TRUE(diagnostics.has_errors());
  expect_round_trip("t\nR$1 a$b $c 1\n", "dollar.cir");
}

// Printed, an expression nests no deeper than its text did: a chain of 150 unary minus signs
// (found by the fuzzer) printed as "(-(-(...)))" nested twice as deep and exceeded the parser's
// limit; so did a sum of 300 terms as "((a + b) + c) ...". Operators keep their meaning where
// precedence and associativity decide: (-x)^2, -(x^2), a - (b - c), 2^3^2 (left-associative),
// 2^(3^2), 2^-3^2, a ? b : c as an operand.
TEST(RoundTrip, ExpressionsPrintAsDeepAsTheyWereWritten) {
  std::string minus(150, '-');
  std::string sum = "1";
  for (int k = 0; k < 300; ++k) sum += "+v(a)";
  expect_round_trip("t\n.param k=" + minus + "2\nB1 a 0 V={" + sum + "}\n", "deep.cir");
  netlist::Diagnostics diagnostics;
  const auto parsed = netlist::parse_text(
      "t\nB1 a 0 V={(-v(a))^2 + -v(a)^2 + (v(a) - (1 - v(b))) * 2^3^2 + 2^(3^2) + 2^-3^2 + (v(a) > 0 ? 1 : 2) * (1 + 2) / (3 * 4)}\n",
      "precedence.cir", diagnostics);
  ASSERT_FALSE(diagnostics.has_errors()) << diagnostics.to_string();
  EXPECT_EQ(netlist::print(parsed),
            "t\nb1 a 0 v={(-v(a)) ^ 2 + -v(a) ^ 2 + (v(a) - (1 - v(b))) * 2 ^ 3 ^ 2 + 2 ^ (3 ^ 2) + 2 ^ -3 ^ 2 + (v(a) > 0 ? 1 : 2) * (1 + 2) / (3 * 4)}\n"
            ".end\n");
}

// A form feed or vertical tab inside a card separates words as a space does (found by the
// fuzzer: ".subckt oute\v x y" took "oute\v" as the name, and its printed ".ends oute\v" lost
// the trailing blank, closing a subcircuit of another name).
TEST(RoundTrip, FormFeedAndVerticalTabSeparateWords) {
  netlist::Diagnostics diagnostics;
  auto parsed = netlist::parse_text("t\n.subckt sub\v x\fy\nR1 x y 1\n.ends sub\nX1 a\vb sub\nR2 a b 1\n",
                                    "blanks.cir", diagnostics);
  ASSERT_FALSE(diagnostics.has_errors()) << diagnostics.to_string();
  EXPECT_EQ(netlist::print(parsed), "t\n.subckt sub x y\nr1 x y 1\n.ends sub\nx1 a b sub\nr2 a b 1\n.end\n");
  expect_round_trip("t\n.subckt oute\v x y pa\n.ends\nV1 in 0 1\n", "blanks.cir");
}

TEST(RoundTrip, PrintsTheExpectedText) {
  netlist::Diagnostics diagnostics;
  auto parsed = netlist::parse_text(
      "title\nR1 A b {2*-x^2} tc=1\nB1 o 0 I={v(a,b) >= 1 && !(time < 1u) ? u(v(a)) : 0}\n"
      "X1 a b sub params: w={k}\n.param k=1.5 j='k+1'\nV1 a 0 DC 1 ac 1 pwl(0 0 1n 1)\n",
      "t.cir", diagnostics);
  EXPECT_EQ(netlist::print(parsed),
            "title\n"
            "r1 a b {2 * -x ^ 2} tc=1\n"
            "b1 o 0 i={v(a,b) >= 1 && !(time < 1e-06) ? u(v(a)) : 0}\n"
            "x1 a b sub params: w={k}\n"
            ".param k={1.5} j={k + 1}\n"
            "v1 a 0 dc 1 ac 1 pwl(0 0 1e-09 1)\n"
            ".end\n");
}

TEST(RoundTrip, EveryKindOfCard) {
  expect_round_trip(
      "every card\n"
      "R1 a b 1k\nC1 a 0 1u ic=1\nL1 a c 1m\nL2 c 0 2m\nK1 L1 L2 0.5\n"
      "V1 a 0 dc 1 ac 1 0 sin(0 1 1k)\nI1 a 0 exp(0 1 1n 1n 2n 1n)\n"
      "E1 e 0 a 0 2\nG1 e 0 a 0 1m\nF1 f 0 V1 2\nH1 h 0 V1 3\n"
      "B1 b 0 V={v(a) > 1 ? 1 : 0}\nD1 a 0 dm 2 off ic=0.7\nS1 a b c 0 sm off\nW1 a b V1 wm on\n"
      "X1 a b s1 p=2\n.subckt s1 x y params: p=1\nR1 x y {p}\n.ends s1\n"
      ".model dm D(is=1e-14)\n.model sm SW vt=1 vh=0.5\n.model wm CSW(it=1m)\n"
      ".param q=1\n.tran 1n 1u 0 1n uic\n.ic v(a)=1 v(a,b)=0\n.nodeset v(c)=0\n"
      ".options reltol=1e-3 method=gear flag\n.save v(a) v(a,b) i(v1) all\n.print tran v(a)\n"
      ".probe v(b)\n.temp 27\n.title Another title\n.op\n",
      "t.cir");
}

}  // namespace
