// The netlist adapter: element kinds, .model parameters, waveforms, .ic and .nodeset reach
// mna as written.
#include <gtest/gtest.h>

#include "mna/device.hpp"
#include "mna/from_netlist.hpp"
#include "netlist/netlist.hpp"

namespace mna {
namespace {

CircuitSpec adapt(const std::string& text) {
  netlist::Diagnostics diagnostics;
  const auto flat = netlist::elaborate(netlist::parse_text(text, "test.cir", diagnostics), diagnostics);
  EXPECT_TRUE(flat.has_value()) << diagnostics.to_string();
  return flat ? circuit_from_netlist(*flat) : CircuitSpec{};
}

const ElementSpec& element(const CircuitSpec& c, const std::string& name) {
  for (const auto& e : c.elements)
    if (e.name == name) return e;
  throw std::runtime_error("no element " + name);
}

TEST(FromNetlist, ElementsModelsWaveformsAndInitialConditions) {
  const CircuitSpec c = adapt(
      "* adapter\n"
      "V1 in 0 DC 2 PWL(0 0 1m 1) \n"
      "I1 0 a PULSE(0 1m 1u)\n"
      "R1 in a 1k\n"
      "C1 a 0 1u IC=0.5\n"
      "D1 a b dmod 2\n"
      "S1 b 0 in 0 smod ON\n"
      "B1 c 0 I=v(a)*2\n"
      "R2 c 0 1\n"
      ".model dmod D(is=1e-12 ideal=0)\n"
      ".model smod SW(vt=0.5 ron=0)\n"
      ".ic v(a)=0.25\n"
      ".nodeset v(b)=0.1\n"
      ".tran 1u 1m\n"
      ".end\n");
  const ElementSpec& v1 = element(c, "v1");
  EXPECT_EQ(v1.type, 'v');
  EXPECT_EQ(v1.value, 2);
  EXPECT_EQ(v1.waveform.shape, Waveform::Shape::piecewise_linear);
  EXPECT_EQ(v1.waveform.parameters, (std::vector<double>{0, 0, 1e-3, 1}));
  EXPECT_EQ(element(c, "i1").waveform.shape, Waveform::Shape::pulse);
  EXPECT_EQ(element(c, "c1").initial_condition, 0.5);
  const ElementSpec& d1 = element(c, "d1");
  EXPECT_EQ(d1.area, 2);
  EXPECT_EQ(d1.model.at("is"), 1e-12);
  const ElementSpec& s1 = element(c, "s1");
  EXPECT_EQ(s1.initially_on, true);
  EXPECT_EQ(s1.model.at("ron"), 0);
  EXPECT_EQ(s1.nodes, (std::vector<std::string>{"b", "0", "in", "0"}));
  const ElementSpec& b1 = element(c, "b1");
  EXPECT_TRUE(b1.expression_is_current);
  EXPECT_NE(b1.expression, nullptr);
  EXPECT_EQ(c.initial_voltages.at("a"), 0.25);
  EXPECT_EQ(c.nodesets.at("b"), 0.1);
}

TEST(FromNetlist, PwlDelayShiftsTimesAndTheRepeatStart) {
  const CircuitSpec c = adapt("* pwl\nV1 a 0 PWL(0 0 1m 1) td=2m\nR1 a 0 1\n.tran 1u 5m\n.end\n");
  EXPECT_EQ(element(c, "v1").waveform.parameters, (std::vector<double>{2e-3, 0, 3e-3, 1}));
  EXPECT_FALSE(element(c, "v1").waveform.repeat_from);
  const CircuitSpec repeated = adapt("* pwl\nV1 a 0 PWL(0 0 1m 1 2m 0) r=1m td=2m\nR1 a 0 1\n.tran 1u 5m\n.end\n");
  EXPECT_EQ(element(repeated, "v1").waveform.repeat_from, 3e-3);
}

}  // namespace
}  // namespace mna
