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
