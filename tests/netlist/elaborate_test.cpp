// Elaboration against hand-computed values: parameters, functions, subcircuit flattening,
// sources, models, includes and the analysis cards.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "netlist/netlist.hpp"

namespace {

using netlist::ElementKind;
using netlist::FlatCircuit;

FlatCircuit elaborate_text(const std::string& text) {
  netlist::Diagnostics diagnostics;
  auto parsed = netlist::parse_text(text, "t.cir", diagnostics);
  auto circuit = netlist::elaborate(parsed, diagnostics);
  EXPECT_TRUE(circuit) << diagnostics.to_string();
  return circuit ? *circuit : FlatCircuit{};
}

FlatCircuit load_data(const std::string& name) {
  netlist::Diagnostics diagnostics;
  auto circuit = netlist::load(std::string(NETLIST_TEST_DATA) + "/" + name, diagnostics);
  EXPECT_TRUE(circuit) << diagnostics.to_string();
  return circuit ? *circuit : FlatCircuit{};
}

const netlist::FlatElement& element(const FlatCircuit& circuit, const std::string& name) {
  const netlist::FlatElement* found = circuit.find_element(name);
  if (!found) throw std::runtime_error("no element " + name);
  return *found;
}

// The value of a resistor whose value is `expression`, after .param lines `params`.
double value_of(const std::string& expression, const std::string& params = "") {
  FlatCircuit circuit = elaborate_text("t\n" + params + "\nR1 a 0 {" + expression + "}\n");
  return circuit.elements.empty() ? std::nan("") : circuit.elements[0].value;
}

TEST(Elaborate, ParametersInDependencyOrder) {
  const std::string params = ".param c={b/a} b={a*3+1}\n.param a=2";
  EXPECT_EQ(value_of("a", params), 2.0);
  EXPECT_EQ(value_of("b", params), 7.0);
  EXPECT_EQ(value_of("c", params), 3.5);
  EXPECT_EQ(value_of("y", ".param x=1k y='x/4'"), 250.0);
}

TEST(Elaborate, OperatorsAndPrecedence) {
  EXPECT_EQ(value_of("1+2*3"), 7.0);
  EXPECT_EQ(value_of("(1+2)*3"), 9.0);
  EXPECT_EQ(value_of("-2^2"), -4.0);  // as ngspice: unary minus binds looser than ^
  EXPECT_EQ(value_of("2**3"), 8.0);
  EXPECT_EQ(value_of("2^3^2"), 64.0);  // left-associative, as ngspice 39 computes it
  EXPECT_EQ(value_of("2**3**2"), 64.0);
  EXPECT_EQ(value_of("2^-3^2"), 1.0 / 512);  // a signed exponent's chain is its own: 2^-(3^2)
  EXPECT_EQ(value_of("-2^2^3"), -64.0);
  EXPECT_EQ(value_of("2^-1"), 0.5);
  EXPECT_EQ(value_of("8/2/2"), 2.0);  // left associative
  EXPECT_EQ(value_of("10-4-3"), 3.0);
  EXPECT_EQ(value_of("1 < 2"), 1.0);
  EXPECT_EQ(value_of("2 <= 1"), 0.0);
  EXPECT_EQ(value_of("3 > 2 == 1"), 1.0);
  EXPECT_EQ(value_of("2 >= 2 && 1 != 1 || !0"), 1.0);
  EXPECT_EQ(value_of("1 && 0"), 0.0);
  EXPECT_EQ(value_of("0 ? 10 : 1 ? 20 : 30"), 20.0);
  EXPECT_EQ(value_of("1 + 1 > 1 ? 5 : 6"), 5.0);
  EXPECT_EQ(value_of("if(0, 1, 2)"), 2.0);
  EXPECT_EQ(value_of("2k*3m"), 6.0);
}

TEST(Elaborate, Functions) {
  EXPECT_EQ(value_of("exp(0)"), 1.0);
  EXPECT_EQ(value_of("ln(1)"), 0.0);
  EXPECT_DOUBLE_EQ(value_of("log(100)"), std::log(100.0));  // ngspice: log is natural
  EXPECT_DOUBLE_EQ(value_of("log10(1000)"), 3.0);
  EXPECT_EQ(value_of("sqrt(16)"), 4.0);
  EXPECT_EQ(value_of("sin(0)+cos(0)+tan(0)+atan(0)"), 1.0);
  EXPECT_DOUBLE_EQ(value_of("atan2(1, 1)"), std::numbers::pi / 4);
  EXPECT_EQ(value_of("sinh(0)+cosh(0)+tanh(0)"), 1.0);
  EXPECT_EQ(value_of("abs(-3)"), 3.0);
  EXPECT_EQ(value_of("min(3, 4)"), 3.0);
  EXPECT_EQ(value_of("max(3, 4)"), 4.0);
  EXPECT_EQ(value_of("pow(2, 10)"), 1024.0);
  EXPECT_EQ(value_of("pwr(-2, 2)"), -4.0);  // sign(x) |x|^y
  EXPECT_EQ(value_of("sgn(-3)"), -1.0);
  EXPECT_EQ(value_of("u(1) + u(0) + u(-1)"), 1.0);
  EXPECT_EQ(value_of("uramp(-1) + uramp(2)"), 2.0);
  EXPECT_EQ(value_of("limit(5, 0, 3) + limit(-1, 0, 3)"), 3.0);
  EXPECT_EQ(value_of("floor(1.5) + ceil(1.5)"), 3.0);
  EXPECT_DOUBLE_EQ(value_of("2*pi"), 2 * std::numbers::pi);
}

TEST(Elaborate, SubcircuitsFlattenWithHierarchicalNames) {
  FlatCircuit circuit = load_data("subckts.cir");
  // outer k=5 passes r = k*3 = 15 to inner; inner's R1 = r*g = 15*10.
  const auto& r1 = element(circuit, "x5.x1.r1");
  EXPECT_EQ(r1.kind, ElementKind::resistor);
  EXPECT_EQ(r1.value, 150.0);
  EXPECT_EQ(r1.nodes, (std::vector<std::string>{"in", "x5.x1.mid"}));
  const auto& r2 = element(circuit, "x5.x1.r2");
  EXPECT_EQ(r2.value, 15.0);
  EXPECT_EQ(r2.nodes, (std::vector<std::string>{"x5.x1.mid", "x5.n1"}));
  EXPECT_EQ(element(circuit, "x5.c1").nodes, (std::vector<std::string>{"x5.n1", "0"}));
  // xa uses outer's default k=2: r = 6, R1 = 60; gnd is the global ground.
  EXPECT_EQ(element(circuit, "xa.x1.r1").value, 60.0);
  EXPECT_EQ(element(circuit, "xa.x1.r2").value, 6.0);
  EXPECT_EQ(element(circuit, "xa.c1").nodes, (std::vector<std::string>{"xa.n1", "0"}));
  EXPECT_EQ(circuit.elements.size(), 7u);
  ASSERT_TRUE(circuit.tran);
  EXPECT_EQ(circuit.tran->step, 1e-9);
  EXPECT_EQ(circuit.tran->stop, 1e-6);
}

TEST(Elaborate, MosfetCardNodesInstanceParametersAndModel) {
  // ngspice's M card: drain gate source bulk model, then L= W= AD= AS= PD= PS= NRD= NRS= M=
  // and OFF; parameters and subcircuit nodes resolve as on any card.
  FlatCircuit circuit = elaborate_text(
      "t\n.param wn=10u\n.subckt inv in out vdd\nM1 out in 0 0 nch W={wn} L=1u AD=20p OFF\n"
      "M2 out in vdd vdd pch W={2*wn} L=1u M=2\n.ends\nX1 a b vdd inv\n"
      ".model nch nmos (level=1 vto=0.7 kp=110u)\n.model pch pmos (vto=-0.7)\n.tran 1n 1u\n");
  const netlist::FlatElement& n = element(circuit, "x1.m1");
  EXPECT_EQ(n.kind, ElementKind::mosfet);
  EXPECT_EQ(n.nodes, (std::vector<std::string>{"b", "a", "0", "0"}));
  EXPECT_EQ(n.model, "nch");
  EXPECT_TRUE(n.off);
  EXPECT_EQ(n.instance_parameters, (std::map<std::string, double>{{"ad", 20e-12}, {"l", 1e-6}, {"w", 10e-6}}));
  const netlist::FlatElement& p = element(circuit, "x1.m2");
  EXPECT_EQ(p.nodes, (std::vector<std::string>{"b", "a", "vdd", "vdd"}));
  EXPECT_FALSE(p.off);
  EXPECT_DOUBLE_EQ(p.instance_parameters.at("w"), 20e-6);
  EXPECT_DOUBLE_EQ(p.instance_parameters.at("m"), 2);
  const auto model = std::find_if(circuit.models.begin(), circuit.models.end(),
                                  [](const netlist::FlatModel& m) { return m.name == "pch"; });
  ASSERT_NE(model, circuit.models.end());
  EXPECT_EQ(model->type, netlist::ModelType::pmos);
  EXPECT_DOUBLE_EQ(*model->get("vto"), -0.7);
}

TEST(Elaborate, GlobalNodesAreSharedByEveryInstance) {
  // ngspice: a .global node inside a subcircuit is the top level's, whichever instance uses it;
  // the subcircuit's other internal nodes stay the instance's own.
  FlatCircuit circuit = elaborate_text(
      "t\n"
      ".subckt half out\n"
      "R1 vdd out 1k\n"
      "R2 out local 1k\n"
      "R3 local 0 1\n"
      ".ends\n"
      "X1 o1 half\n"
      "X2 o2 half\n"
      "Vdd vdd 0 6\n"
      ".global vdd\n");
  EXPECT_EQ(element(circuit, "x1.r1").nodes, (std::vector<std::string>{"vdd", "o1"}));
  EXPECT_EQ(element(circuit, "x2.r1").nodes, (std::vector<std::string>{"vdd", "o2"}));
  EXPECT_EQ(element(circuit, "x2.r2").nodes, (std::vector<std::string>{"o2", "x2.local"}));
}

TEST(Elaborate, SubcircuitReferencesBecomeHierarchical) {
  FlatCircuit circuit = elaborate_text(
      "t\n"
      ".subckt stage in out params: gain=3\n"
      "Vs in mid 0\n"
      "B1 out 0 V={gain*v(mid) + i(vs)}\n"
      "F1 out 0 vs 2\n"
      "D1 mid 0 dlocal\n"
      "W1 mid 0 vs wsw\n"
      ".model dlocal D(is={gain*1e-15})\n"
      ".model wsw CSW(it=1m)\n"
      ".ends\n"
      "X1 a b stage gain=4\n");
  const auto& b1 = element(circuit, "x1.b1");
  EXPECT_TRUE(b1.behavioral_is_voltage);
  EXPECT_EQ(netlist::print(*b1.expression), "4 * v(x1.mid) + i(x1.vs)");
  EXPECT_EQ(b1.nodes, (std::vector<std::string>{"b", "0"}));
  EXPECT_EQ(element(circuit, "x1.vs").nodes, (std::vector<std::string>{"a", "x1.mid"}));
  EXPECT_EQ(element(circuit, "x1.f1").controls, (std::vector<std::string>{"x1.vs"}));
  EXPECT_EQ(element(circuit, "x1.d1").model, "x1.dlocal");
  EXPECT_EQ(element(circuit, "x1.w1").model, "x1.wsw");
  const netlist::FlatModel* model = circuit.find_model("x1.dlocal");
  ASSERT_NE(model, nullptr);
  EXPECT_EQ(model->type, netlist::ModelType::diode);
  EXPECT_EQ(model->get("is"), 4e-15);
}

TEST(Elaborate, SourcesAndControlledSources) {
  FlatCircuit circuit = load_data("sources.cir");
  EXPECT_EQ(element(circuit, "v1").source.dc, 1.0);
  EXPECT_FALSE(element(circuit, "v1").source.waveform);
  const auto& pulse = *element(circuit, "v2").source.waveform;
  EXPECT_EQ(pulse.kind, netlist::WaveformKind::pulse);
  EXPECT_EQ(pulse.args, (std::vector<double>{0, 1, 1e-9, 2e-9, 3e-9, 4e-9, 10e-9, 5}));
  const auto& sine = *element(circuit, "v3").source.waveform;
  EXPECT_EQ(sine.kind, netlist::WaveformKind::sin);
  EXPECT_EQ(sine.args, (std::vector<double>{0.5, 1, 1e6, 0, 0, 90}));
  EXPECT_EQ(element(circuit, "v4").source.waveform->args,
            (std::vector<double>{0, 1, 1e-6, 1e-6, 2e-6, 1e-6}));
  const auto& pwl = *element(circuit, "v5").source.waveform;
  EXPECT_EQ(pwl.kind, netlist::WaveformKind::pwl);
  EXPECT_EQ(pwl.args, (std::vector<double>{0, 0, 1e-6, 1, 2e-6, 1, 3e-6, 0}));
  EXPECT_EQ(pwl.repeat_from, 1e-6);
  EXPECT_EQ(pwl.delay, 0.5e-6);
  // Without parentheses, as SPICE also reads them: the same waveforms.
  EXPECT_EQ(element(circuit, "v6").source.waveform->kind, netlist::WaveformKind::pulse);
  EXPECT_EQ(element(circuit, "v6").source.waveform->args, pulse.args);
  EXPECT_EQ(element(circuit, "v7").source.dc, 0.5);
  EXPECT_EQ(element(circuit, "v7").source.waveform->kind, netlist::WaveformKind::sin);
  EXPECT_EQ(element(circuit, "v7").source.waveform->args, (std::vector<double>{0.5, 1, 1e6}));
  EXPECT_EQ(element(circuit, "v8").source.waveform->args, (std::vector<double>{0, 0, 1e-6, 1}));
  EXPECT_EQ(element(circuit, "v8").source.waveform->delay, 0.5e-6);
  EXPECT_EQ(element(circuit, "v10").source.waveform->kind, netlist::WaveformKind::sffm);
  EXPECT_EQ(element(circuit, "v10").source.waveform->args, (std::vector<double>{0, 1, 1e4, 2, 1e3}));
  // Options inside the parentheses as well as after them, as ngspice reads them.
  EXPECT_EQ(element(circuit, "v9").source.waveform->repeat_from, 1e-6);
  EXPECT_EQ(element(circuit, "v9").source.waveform->delay, 0.5e-6);
  EXPECT_EQ(element(circuit, "i1").kind, ElementKind::current_source);
  EXPECT_EQ(element(circuit, "i1").source.dc, 1e-3);
  EXPECT_EQ(element(circuit, "i2").source.dc, 0.0);
  EXPECT_EQ(element(circuit, "i2").source.waveform->args, (std::vector<double>{0, 0, 1e-9, 1e-3}));
  // POLY: a B source of SPICE's polynomial, zero coefficients left out.
  EXPECT_EQ(element(circuit, "e2").kind, ElementKind::behavioral);
  EXPECT_TRUE(element(circuit, "e2").behavioral_is_voltage);
  EXPECT_EQ(netlist::print(*element(circuit, "e2").expression), "1 + 3 * v(b,0)");
  EXPECT_EQ(element(circuit, "h2").kind, ElementKind::behavioral);
  EXPECT_EQ(netlist::print(*element(circuit, "h2").expression), "2 * i(v1) * i(v1)");
  // vol=, cur=, value=: B sources too.
  EXPECT_EQ(element(circuit, "e3").kind, ElementKind::behavioral);
  EXPECT_TRUE(element(circuit, "e3").behavioral_is_voltage);
  EXPECT_EQ(netlist::print(*element(circuit, "e3").expression), "2 * v(a)");
  EXPECT_EQ(element(circuit, "g2").kind, ElementKind::behavioral);
  EXPECT_FALSE(element(circuit, "g2").behavioral_is_voltage);
  EXPECT_EQ(element(circuit, "g2").nodes, (std::vector<std::string>{"0", "u"}));
  EXPECT_EQ(element(circuit, "e1").nodes, (std::vector<std::string>{"h", "0", "a", "0"}));
  EXPECT_EQ(element(circuit, "e1").value, 2.0);
  EXPECT_EQ(element(circuit, "g1").value, 1e-3);
  EXPECT_EQ(element(circuit, "f1").controls, (std::vector<std::string>{"v1"}));
  EXPECT_EQ(element(circuit, "h1").value, 100.0);
  EXPECT_EQ(element(circuit, "l1").initial_condition, 1e-3);
  EXPECT_EQ(element(circuit, "k1").controls, (std::vector<std::string>{"l1", "l2"}));
  EXPECT_EQ(element(circuit, "k1").value, 0.99);
  EXPECT_EQ(element(circuit, "w1").initially_on, true);
  EXPECT_EQ(element(circuit, "w1").controls, (std::vector<std::string>{"v1"}));
  ASSERT_EQ(circuit.initial_conditions.size(), 2u);
  EXPECT_EQ(circuit.initial_conditions[0].node, "a");
  EXPECT_EQ(circuit.initial_conditions[0].value, 1.0);
  EXPECT_EQ(circuit.initial_conditions[1].reference, "0");
  ASSERT_EQ(circuit.nodesets.size(), 1u);
  EXPECT_EQ(circuit.nodesets[0].value, 0.5);
  // .print tran v(a) v(b) i(v1) and .probe v(c): the analysis word is not an output.
  ASSERT_EQ(circuit.saves.size(), 4u);
  EXPECT_EQ(circuit.saves[2].kind, netlist::OutputRequest::Kind::branch_current);
  EXPECT_EQ(circuit.saves[2].element, "v1");
  EXPECT_EQ(circuit.saves[3].node, "c");
  EXPECT_EQ(circuit.temperature, 50.0);
}

TEST(Elaborate, SwitchedBuck) {
  FlatCircuit circuit = load_data("buck.cir");
  EXPECT_EQ(circuit.title, "Buck converter with an ideal switch and diode");
  // ton = duty / fsw = 0.4 / 100k = 4us, period = 10us.
  const auto& gate = *element(circuit, "vgate").source.waveform;
  EXPECT_DOUBLE_EQ(gate.args[5], 4e-6);
  EXPECT_DOUBLE_EQ(gate.args[6], 1e-5);
  EXPECT_EQ(element(circuit, "vin").source.dc, 12.0);
  const auto& s1 = element(circuit, "s1");
  EXPECT_EQ(s1.nodes, (std::vector<std::string>{"in", "sw", "g", "0"}));
  EXPECT_EQ(s1.model, "swmod");
  EXPECT_EQ(s1.initially_on, false);
  EXPECT_EQ(element(circuit, "rload").value, 2.5);
  const netlist::FlatModel* diode = circuit.find_model("dideal");
  ASSERT_NE(diode, nullptr);
  EXPECT_EQ(diode->get("ideal"), 1.0);
  EXPECT_EQ(diode->get("vfwd"), 0.3);
  EXPECT_EQ(circuit.find_model("swmod")->get("roff"), 1e6);
  ASSERT_TRUE(circuit.tran);
  EXPECT_EQ(circuit.tran->step, 1e-6);
  EXPECT_EQ(circuit.tran->stop, 2e-3);
  EXPECT_EQ(circuit.tran->start, 0.0);
  EXPECT_EQ(circuit.tran->max_step, 100e-9);
  EXPECT_TRUE(circuit.tran->use_initial_conditions);
  EXPECT_EQ(circuit.find_option("reltol")->number, 1e-4);
  EXPECT_EQ(circuit.find_option("method")->word, "gear");
  EXPECT_EQ(circuit.find_option("nosuch"), nullptr);
}

// The area factor after the model name (SPICE2/3) or as area= (ngspice 39); 1 if not written.
TEST(Elaborate, DiodeAreaEitherPositionalOrKeyword) {
  FlatCircuit circuit = elaborate_text("t\nD1 a 0 dm 3\nD2 a 0 dm area=2.5\nD3 a 0 dm\n"
                                       ".model dm d(is=1e-14 bv=5 nbv=1.5)\n");
  EXPECT_EQ(element(circuit, "d1").value, 3.0);
  EXPECT_EQ(element(circuit, "d2").value, 2.5);
  EXPECT_EQ(element(circuit, "d3").value, 1.0);
  EXPECT_TRUE(circuit.warnings.empty());  // nbv is a diode parameter
}

TEST(Elaborate, OptionsAreKeptWhateverTheirName) {
  FlatCircuit circuit = elaborate_text("t\n.options padsim_order=3 noinit\n.option method=trap\n"
                                       ".options padsim_order=4\n");
  EXPECT_EQ(circuit.find_option("padsim_order")->number, 4.0);
  EXPECT_FALSE(circuit.find_option("noinit")->number);
  EXPECT_EQ(circuit.find_option("method")->word, "trap");
  EXPECT_EQ(circuit.options.size(), 4u);
}

TEST(Elaborate, InitialConditionGivenAgainIsWarnedOfAndTheLastKept) {
  FlatCircuit circuit = elaborate_text("t\nV1 in 0 1\nR1 in a 1k\nC1 a 0 1u\n.ic v(a)=1\n.ic v(a)=2 v(in)=1\n"
                                       ".tran 1u 1m uic\n");
  ASSERT_EQ(circuit.warnings.size(), 1u);
  EXPECT_EQ(circuit.warnings[0].severity, netlist::Severity::warning);
  EXPECT_EQ(circuit.warnings[0].message, ".ic of node 'a' is given again; this value replaces the earlier one");
  EXPECT_EQ(circuit.warnings[0].where.begin.line, 6);
  EXPECT_EQ(circuit.warnings[0].where.begin.column, 7);
  ASSERT_EQ(circuit.initial_conditions.size(), 3u);
  EXPECT_EQ(circuit.initial_conditions[1].value, 2.0);  // after the first: the one in force
}

TEST(Elaborate, IncludesAndLibrarySectionsRelativeToTheIncludingFile) {
  FlatCircuit circuit = load_data("include_main.cir");
  EXPECT_EQ(element(circuit, "x1.r1").value, 1000.0);  // rleaf from ../leaf.inc
  EXPECT_EQ(element(circuit, "d1").model, "dfast");
  EXPECT_EQ(circuit.find_model("dfast")->get("is"), 1e-12);
  EXPECT_EQ(circuit.find_model("dslow"), nullptr);  // the other section is not read
}

TEST(Elaborate, CommentsContinuationsAndCase) {
  FlatCircuit circuit = load_data("comments.cir");
  EXPECT_EQ(element(circuit, "r1").nodes, (std::vector<std::string>{"in", "out"}));
  EXPECT_EQ(element(circuit, "r2").value, 2000.0);
  EXPECT_EQ(element(circuit, "c1").value, 1e-6);
  EXPECT_EQ(element(circuit, "c1").initial_condition, 0.5);
  EXPECT_EQ(element(circuit, "v1").nodes, (std::vector<std::string>{"in", "0"}));
  EXPECT_EQ(element(circuit, "v1").source.dc, 5.0);
  EXPECT_EQ(circuit.elements.size(), 4u);  // nothing after .end
  ASSERT_EQ(circuit.warnings.size(), 1u);  // the note about .control
  EXPECT_EQ(circuit.warnings[0].severity, netlist::Severity::note);
}

TEST(Elaborate, BehavioralExpressionsKeepConditions) {
  FlatCircuit circuit = load_data("expressions.cir");
  const auto& b1 = element(circuit, "b1");
  EXPECT_EQ(netlist::print(*b1.expression),
            "v(in) > 0.5 ? 2 * v(in,0) : -i(v1) ^ 2 + time");
  const auto& b2 = element(circuit, "b2");
  EXPECT_FALSE(b2.behavioral_is_voltage);
  EXPECT_EQ(netlist::print(*b2.expression), "limit(v(in), -1, 1) * 2");
  // fns = 1+0+0+2+2+0+1+0+0; more = 0+0+1+0+1+1+2+4-4; rest = -1+1+0+3+1+2
  EXPECT_DOUBLE_EQ(element(circuit, "r1").value, 6.0);
  EXPECT_EQ(element(circuit, "r2").value, 5.0 + 6.0);
}

// ---- the hierarchy check: card count, depth ------------------------------------------------

struct Elaborated {
  netlist::Diagnostics diagnostics;
  std::optional<FlatCircuit> circuit;

  std::vector<netlist::Diagnostic> errors() const {
    std::vector<netlist::Diagnostic> errors;
    for (const netlist::Diagnostic& d : diagnostics.all())
      if (d.severity == netlist::Severity::error) errors.push_back(d);
    return errors;
  }
};

Elaborated elaborate_limited(const std::string& text,
                             std::size_t max_cards = netlist::max_expanded_cards) {
  Elaborated result;
  auto parsed = netlist::parse_text(text, "t.cir", result.diagnostics);
  EXPECT_FALSE(result.diagnostics.has_errors()) << result.diagnostics.to_string();
  result.circuit = netlist::elaborate(parsed, result.diagnostics, max_cards);
  return result;
}

// The 1-based line of the first occurrence of `needle`.
int line_of(const std::string& text, const std::string& needle) {
  std::size_t at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
}

// Subcircuits l1 .. l<levels>, each with `fanout` instances of the one below, over l0 (one
// resistor, or `leaf`); the top level has V1 and one instance of l<levels>: 1 + fanout^levels
// elements.
std::string nested(int levels, int fanout, const std::string& leaf = "R1 a 0 1\n") {
  std::string text = "t\n.subckt l0 a\n" + leaf + ".ends\n";
  for (int level = 1; level <= levels; ++level) {
    text += ".subckt l" + std::to_string(level) + " a\n";
    for (int i = 0; i < fanout; ++i)  // appended in pieces: GCC 12 warns (-Wrestrict) on "X" + ...
      text.append("X").append(std::to_string(i)).append(" a l")
          .append(std::to_string(level - 1)).append("\n");
    text += ".ends\n";
  }
  return text + "V1 n 0 1\nXtop n l" + std::to_string(levels) + "\n";
}

void expect_one_error(const Elaborated& e, const std::string& message, int line, int column) {
  EXPECT_FALSE(e.circuit);
  auto errors = e.errors();
  ASSERT_EQ(errors.size(), 1u) << e.diagnostics.to_string();
  EXPECT_EQ(errors[0].message, message);
  EXPECT_EQ(errors[0].where.begin.line, line);
  EXPECT_EQ(errors[0].where.begin.column, column);
}

std::string over_limit(std::size_t max_cards) {
  return "the circuit expands to more than " + std::to_string(max_cards) +
         " cards (each subcircuit instance counts, with its body's cards)";
}

TEST(Elaborate, CardCountAtTheLimitIsBuiltAndOneMoreIsRefusedAtTheTopLevelInstance) {
  // 65 elements: 1 + 4^3; 85 X cards: 1 + 4 + 4^2 + 4^3; 4 .subckt cards at the top level.
  std::string text = nested(3, 4);
  Elaborated at_limit = elaborate_limited(text, 154);
  ASSERT_TRUE(at_limit.circuit) << at_limit.diagnostics.to_string();
  EXPECT_EQ(at_limit.circuit->elements.size(), 65u);
  expect_one_error(elaborate_limited(text, 153), over_limit(153), line_of(text, "Xtop"), 1);
}

TEST(Elaborate, CardCountResolvesSubcircuitsAsTheExpansionDoes) {
  // inner is defined in outer's body; user's instances inside outer see it.
  std::string text =
      "t\n"
      ".subckt user a\nXq a inner\n.ends\n"
      ".subckt outer a\n.subckt inner b\nR1 b 0 1\nR2 b 0 1\n.ends\nX1 a user\nX2 a user\n.ends\n"
      "X1 n outer\n";
  // Top level: 2 .subckt cards and X1 (1); outer: .subckt inner, X1 and X2 (3); each user: Xq
  // (1) and inner's R1 and R2 (2).
  Elaborated at_limit = elaborate_limited(text, 12);
  ASSERT_TRUE(at_limit.circuit) << at_limit.diagnostics.to_string();
  EXPECT_EQ(at_limit.circuit->elements.size(), 4u);
  EXPECT_TRUE(at_limit.circuit->find_element("x1.x2.xq.r2"));
  expect_one_error(elaborate_limited(text, 11), over_limit(11), line_of(text, "X1 n outer"), 1);
}

TEST(Elaborate, TenLevelsOfTenInstancesAreRefusedWithoutBuildingThem) {
  // 1 + 10^10 elements: counted per subcircuit, refused in milliseconds (building them until
  // the limit took 40 s).
  std::string text = nested(10, 10);
  expect_one_error(elaborate_limited(text), over_limit(10'000'000), line_of(text, "Xtop"), 1);
}

TEST(Elaborate, TenLevelsOfTenInstancesOfEmptySubcircuitsAreRefusedWithoutExpandingThem) {
  // No element below the top level, but 10^10 instances to expand (counting elements only, this
  // was 1: padsim was still expanding after 10 minutes, deaf to SIGTERM).
  std::string text = nested(10, 10, "");
  auto start = std::chrono::steady_clock::now();
  expect_one_error(elaborate_limited(text), over_limit(10'000'000), line_of(text, "Xtop"), 1);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
}

TEST(Elaborate, ModelsInSubcircuitsCountPerInstance) {
  // Each instance elaborates its own copy of a model defined in its subcircuit: 10^6 instances
  // of 100 models are 10^8 models to build.
  std::string models;
  for (int i = 0; i < 100; ++i) models += ".model d" + std::to_string(i) + " d\n";
  std::string text = nested(6, 10, models);
  expect_one_error(elaborate_limited(text), over_limit(10'000'000), line_of(text, "Xtop"), 1);
}

TEST(Elaborate, CardCountSaturates) {
  // 2^64 elements: a wrapping count would be small.
  std::string text = nested(64, 2);
  expect_one_error(elaborate_limited(text), over_limit(10'000'000), line_of(text, "Xtop"), 1);
}

// Subcircuits s0 (one resistor) .. s<n-1>, each instantiating the one below.
std::string chain(int n) {
  std::string text = "t\n.subckt s0 a\nR1 a 0 1\n.ends\n";
  for (int k = 1; k < n; ++k)
    text += ".subckt s" + std::to_string(k) + " a\nX1 a s" + std::to_string(k - 1) + "\n.ends\n";
  return text;
}

TEST(Elaborate, SubcircuitsNestAtMostOneHundredLevels) {
  std::string hundred = chain(100) + "X1 n s99\n";
  Elaborated fine = elaborate_limited(hundred);
  ASSERT_TRUE(fine.circuit) << fine.diagnostics.to_string();
  EXPECT_EQ(fine.circuit->elements.size(), 1u);
  std::string name;  // x1. (the top-level instance) and x1. in s99 .. s1
  for (int level = 0; level < 100; ++level) name += "x1.";
  EXPECT_EQ(fine.circuit->elements[0].name, name + "r1");

  // The 101st level: reported at the X card that would open it (in s1, instantiating s0).
  std::string deeper = chain(101) + "X1 n s100\n";
  expect_one_error(elaborate_limited(deeper), "subcircuits nest more than 100 levels deep",
                   line_of(deeper, "X1 a s0"), 6);

  // s99 counted first where it nests 100 levels, then reached one level deeper through u: the
  // count of s99 is reused only where it cannot nest too deep.
  std::string reused = chain(100) + ".subckt u a\nX1 a s99\n.ends\nX1 n s99\nX2 n u\n";
  expect_one_error(elaborate_limited(reused), "subcircuits nest more than 100 levels deep",
                   line_of(reused, "X1 a s0"), 6);
}

}  // namespace
