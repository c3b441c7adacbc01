// Structural singularities are reported with the nodes and elements at fault.
#include <gtest/gtest.h>

#include "helpers.hpp"
#include "mna/structure.hpp"

namespace mna::test {
namespace {

std::string structure_error(const CircuitSpec& c, StartKind start) {
  Model model(c, {.tstep = 1e-6, .tstop = 1e-3});
  try {
    check_structure(model, start);
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

TEST(Structure, WellPosedCircuitPasses) {
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 1);
  c.add("r1", {"in", "out"}, 1e3);
  c.add("c1", {"out", "0"}, 1e-6);
  EXPECT_EQ(structure_error(c, StartKind::operating_point), "");
}

TEST(Structure, NodeBehindCapacitorHasNoDcPath) {
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 1);
  c.add("c1", {"in", "mid"}, 1e-6);
  c.add("c2", {"mid", "0"}, 1e-6);
  const std::string error = structure_error(c, StartKind::operating_point);
  EXPECT_NE(error.find("no DC path to ground from node(s) mid"), std::string::npos) << error;
  EXPECT_NE(error.find("c1"), std::string::npos) << error;
  EXPECT_EQ(structure_error(c, StartKind::initial_conditions), "");  // fine with uic
}

TEST(Structure, CutSetOfCurrentSources) {
  CircuitSpec c;
  c.add("i1", {"0", "a"}, 1e-3);
  c.add("i2", {"b", "0"}, 1e-3);
  c.add("r1", {"a", "b"}, 1e3);
  const std::string error = structure_error(c, StartKind::initial_conditions);
  EXPECT_NE(error.find("no path to ground from node(s) a, b"), std::string::npos) << error;
  EXPECT_NE(error.find("i1, i2"), std::string::npos) << error;
  EXPECT_NE(error.find("cut-set of current sources"), std::string::npos) << error;
}

TEST(Structure, LoopOfVoltageSources) {
  CircuitSpec c;
  c.add("v1", {"a", "0"}, 1);
  c.add("v2", {"a", "b"}, 1);
  c.add("e1", {"b", "0", "a", "0"}, 1);
  c.add("r1", {"a", "0"}, 1);
  const std::string error = structure_error(c, StartKind::initial_conditions);
  EXPECT_NE(error.find("loop of voltage sources: "), std::string::npos) << error;
  for (const char* element : {"v1", "v2", "e1"}) EXPECT_NE(error.find(element), std::string::npos) << error;
  EXPECT_EQ(error.find("r1"), std::string::npos) << error;
}

TEST(Structure, InductorAcrossVoltageSourceOnlyAtDc) {
  CircuitSpec c;
  c.add("v1", {"a", "0"}, 1);
  c.add("l1", {"a", "0"}, 1e-3);
  const std::string error = structure_error(c, StartKind::operating_point);
  EXPECT_NE(error.find("loop of voltage sources and inductors: v1, l1"), std::string::npos) << error;
  EXPECT_EQ(structure_error(c, StartKind::initial_conditions), "");
}

TEST(Structure, ClosedIdealSwitchClosingALoopOfSourcesInTheStartMode) {
  CircuitSpec c;
  c.add("v1", {"a", "0"}, 1);
  c.add("v2", {"b", "0"}, 2);
  c.add("vc", {"ctl", "0"}, 1);
  auto& s = c.add("s1", {"a", "b", "ctl", "0"});
  s.model = {{"ron", 0.0}, {"vt", 0.5}};
  Model m(c, {});
  EXPECT_NO_THROW(check_structure(m, StartKind::initial_conditions));
  try {
    check_mode_structure(m, StartKind::initial_conditions, {1});
    FAIL() << "no error";
  } catch (const ModelError& e) {
    const std::string error = e.what();
    EXPECT_NE(error.find("with the initial switch and diode states: loop of voltage sources"), std::string::npos) << error;
    EXPECT_NE(error.find("s1"), std::string::npos) << error;
  }
  EXPECT_NO_THROW(check_mode_structure(m, StartKind::initial_conditions, {0}));
}

TEST(Structure, OpenIdealSwitchIsolatingACurrentSource) {
  CircuitSpec c;
  c.add("i1", {"0", "m"}, 1e-3);
  c.add("vc", {"ctl", "0"}, 0);
  c.add("s1", {"m", "0", "ctl", "0"}).model = {{"roff", infinity}, {"vt", 0.5}};
  Model m(c, {});
  EXPECT_NO_THROW(check_structure(m, StartKind::initial_conditions));
  try {
    check_mode_structure(m, StartKind::initial_conditions, {0});
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("no path to ground from node(s) m; only i1"), std::string::npos) << e.what();
  }
}

TEST(Structure, LoopMessageSaysWhatTheLoopHolds) {
  CircuitSpec sources;
  sources.add("v1", {"a", "0"}, 1);
  sources.add("v2", {"a", "0"}, 2);
  EXPECT_NE(structure_error(sources, StartKind::operating_point).find("loop of voltage sources: v1, v2 ("), std::string::npos)
      << structure_error(sources, StartKind::operating_point);
  CircuitSpec inductors;
  inductors.add("v1", {"a", "0"}, 1);
  inductors.add("r1", {"a", "b"}, 1);
  inductors.add("l1", {"b", "c"}, 1e-3);
  inductors.add("l2", {"c", "b"}, 1e-3);
  const std::string error = structure_error(inductors, StartKind::operating_point);
  EXPECT_NE(error.find("loop of inductors: l1, l2 (the currents around it are undetermined at DC"), std::string::npos) << error;
}

TEST(Structure, OneElementCutSetSaysConnects) {
  CircuitSpec c;
  c.add("v1", {"in", "0"}, 1);
  c.add("c1", {"in", "mid"}, 1e-6);
  c.add("r1", {"mid", "x"}, 1);
  const std::string error = structure_error(c, StartKind::operating_point);
  EXPECT_NE(error.find("no DC path to ground from node(s) mid, x; only c1 connects them"), std::string::npos) << error;
}

// A current source whose current reads the voltage across its own nodes is a conductance
// (G1 a 0 a 0 1m, B1 a 0 I={v(a)/1k}; ngspice runs both): it ties the node down as a resistor
// would. They were refused as a cut-set of current sources. One reading another node is not.
TEST(Structure, CurrentSourceReadingItsOwnNodesIsAPath) {
  CircuitSpec g;
  g.add("i1", {"0", "a"}, 1e-3);
  g.add("g1", {"a", "0", "a", "0"}, 1e-3);
  EXPECT_EQ(structure_error(g, StartKind::operating_point), "");
  EXPECT_EQ(structure_error(g, StartKind::initial_conditions), "");
  CircuitSpec b;
  b.add("i1", {"0", "a"}, 1e-3);
  auto& b1 = b.add("b1", {"a", "0"});
  b1.expression = binary(netlist::BinaryOperator::divide, voltage("a"), number(1e3));
  b1.expression_is_current = true;
  EXPECT_EQ(structure_error(b, StartKind::operating_point), "");
  CircuitSpec other;
  other.add("i1", {"0", "a"}, 1e-3);
  other.add("g1", {"a", "0", "b", "0"}, 1e-3);
  other.add("r1", {"b", "0"}, 1e3);
  EXPECT_NE(structure_error(other, StartKind::operating_point).find("no DC path to ground from node(s) a; only i1, g1 connect"),
            std::string::npos)
      << structure_error(other, StartKind::operating_point);
}

// The operating point holds .ic node voltages: one on a node a V or E source (or an inductor,
// a short at DC) fixes leaves that source's current undetermined. It was found only as singular
// equations ("do not determine i(v1)"), the .ic unnamed; the error is now at the .ic.
TEST(Structure, InitialConditionOnANodeASourceFixesNamesTheIcAndTheSource) {
  auto held_error = [](const CircuitSpec& c) -> std::pair<std::string, std::string> {
    Model model(c, {.tstep = 1e-6, .tstop = 1e-3});
    EXPECT_NO_THROW(check_structure(model, StartKind::initial_conditions));  // uic holds nothing
    try {
      check_structure(model, StartKind::operating_point);
    } catch (const ModelError& e) {
      return {e.what(), e.initial_condition()};
    }
    return {};
  };
  CircuitSpec rc;
  rc.add("v1", {"a", "0"}, 1);
  rc.add("r1", {"a", "b"}, 1e3);
  rc.add("c1", {"b", "0"}, 1e-6);
  rc.initial_voltages = {{"a", 0}, {"b", 0}};
  const auto [message, node] = held_error(rc);
  EXPECT_EQ(message, ".ic v(a) is on a node that v1 fixes: the operating point holds .ic voltages, which leaves the "
                     "current of v1 undetermined; drop this .ic, or start from initial conditions (uic)");
  EXPECT_EQ(node, "a");
  rc.initial_voltages = {{"b", 0}};
  EXPECT_EQ(held_error(rc).first, "");
  CircuitSpec e;
  e.add("v1", {"in", "0"}, 1);
  e.add("r0", {"in", "0"}, 1e3);
  e.add("e1", {"x", "a", "in", "0"}, 2.0);
  e.add("l1", {"x", "0"}, 1e-3);
  e.add("r1", {"a", "0"}, 1e3);
  e.initial_voltages = {{"a", 2}};
  EXPECT_EQ(held_error(e).first,
            ".ic v(a) is on a node that e1, l1 fix (inductors are shorts at DC): the operating point holds .ic voltages, "
            "which leaves the currents of e1, l1 undetermined; drop this .ic, or start from initial conditions (uic)");
}

padae::Predicates no_predicates(const Model& m) { return padae::Predicates(static_cast<std::size_t>(m.predicate_count()), 0); }

TEST(Structure, SingularLinearEquationsNameTheUndeterminedUnknowns) {
  CircuitSpec c;  // E1 drives its own control with gain 1: v(a) = v(a)
  c.add("e1", {"a", "0", "a", "0"}, 1.0);
  c.add("r1", {"a", "0"}, 1.0);
  Model m(c, {.tstep = 1e-6, .tstop = 1e-3});
  EXPECT_NO_THROW(check_structure(m, StartKind::operating_point));
  const std::string error = singular_linear_equations(m, StartKind::operating_point, no_predicates(m), 0, 1e-3);
  EXPECT_NE(error.find("the circuit equations are singular at the operating point (linear, rank 1 of 2): they do not "
                       "determine v(a), i(e1)"),
            std::string::npos)
      << error;
  EXPECT_NE(singular_linear_equations(m, StartKind::initial_conditions, no_predicates(m), 0, 1e-3).find("at the start"),
            std::string::npos);
}

TEST(Structure, SingularLinearEquationsNameTheElementsAtTheUndeterminedNodes) {
  // b and d hang from a through an open switch of ROFF 1e20 only, which rounding loses beside
  // R1's 1 mS: v(b) and v(d) are undetermined, and s1 and r1 are what connects them.
  CircuitSpec c;
  c.add("v1", {"a", "0"}, 1.0);
  c.add("vc", {"c", "0"}, 0.0);
  c.add("s1", {"a", "b", "c", "0"}).model = {{"vt", 0.5}, {"ron", 1}, {"roff", 1e20}};
  c.add("r1", {"b", "d"}, 1e3);
  Model m(c, {.tstep = 1e-6, .tstop = 1e-3});
  const std::string error = singular_linear_equations(m, StartKind::operating_point, no_predicates(m), 0, 1e-3);
  EXPECT_NE(error.find("they do not determine v(b), v(d), where s1, r1 connect"), std::string::npos) << error;
}

TEST(Structure, RegularOrNonlinearEquationsAreNotCalledSingular) {
  CircuitSpec regular;  // gain 2: v(a) = 2 v(a) has the one solution 0
  regular.add("e1", {"a", "0", "a", "0"}, 2.0);
  regular.add("r1", {"a", "0"}, 1.0);
  Model m(regular, {.tstep = 1e-6, .tstop = 1e-3});
  EXPECT_EQ(singular_linear_equations(m, StartKind::operating_point, no_predicates(m), 0, 1e-3), "");
  CircuitSpec stiff;  // 1e12 beside 1e-12 siemens: ill-scaled, not singular
  stiff.add("v1", {"a", "0"}, 1.0);
  stiff.add("r1", {"a", "b"}, 1e-12);
  stiff.add("r2", {"b", "0"}, 1e12);
  Model s(stiff, {.tstep = 1e-6, .tstop = 1e-3});
  EXPECT_EQ(singular_linear_equations(s, StartKind::operating_point, no_predicates(s), 0, 1e-3), "");
}

TEST(Structure, ModelErrorsNameTheElement) {
  CircuitSpec c;
  c.add("f1", {"a", "0"}, 1).controls = {"vmissing"};
  c.add("r1", {"a", "0"}, 1);
  EXPECT_THROW(Model(c, {}), ModelError);
  CircuitSpec twice;
  twice.add("r1", {"a", "0"}, 1.0);
  twice.add("r1", {"a", "0"}, 2.0);
  EXPECT_THROW(Model(twice, {}), ModelError);
  CircuitSpec bad;
  bad.add("r1", {"a", "0"}, 0.0);
  try {
    Model m(bad, {});
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("r1"), std::string::npos);
  }
}

}  // namespace
}  // namespace mna::test
