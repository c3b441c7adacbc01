// The netlist as written: one struct per kind of card, names lower-cased, values kept as
// expressions (numbers are Number expressions), every token with its position. Includes are
// resolved while parsing (their cards are kept inside the include card) so that elaboration
// needs no file access; subcircuit bodies are nested.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "netlist/expression.hpp"
#include "netlist/position.hpp"
#include "netlist/source.hpp"

namespace netlist::ast {

struct Word {
  std::string text;  // lower case, except file paths
  SourceRange where;
};

struct Assignment {  // name=value
  Word name;
  ExpressionPtr value;
};

struct Card;

// R C L: name n+ n- value [ic=...]
struct TwoTerminal {
  Word name, positive, negative;
  ExpressionPtr value;
  std::vector<Assignment> parameters;
};

// K: name inductor1 inductor2 coefficient
struct Coupling {
  Word name, first, second;
  ExpressionPtr value;
};

// One specification of an independent source: kind "dc", "ac", "pulse", "sin", "exp", "sffm", "pwl",
// or empty for a bare DC value. `options` are pwl's r= and td=.
struct SourceSpec {
  Word kind;
  std::vector<ExpressionPtr> args;
  std::vector<Assignment> options;
};

// V I: name n+ n- specs
struct IndependentSource {
  Word name, positive, negative;
  std::vector<SourceSpec> specs;
};

// E G: name n+ n- nc+ nc- gain
struct VoltageControlled {
  Word name, positive, negative, control_positive, control_negative;
  ExpressionPtr gain;
};

// F H: name n+ n- vcontrol gain
struct CurrentControlled {
  Word name, positive, negative, control;
  ExpressionPtr gain;
};

// E G: name n+ n- poly(n) nc1+ nc1- ... ncn+ ncn- p0 p1 ...; F H: name n+ n- poly(n) v1 ... vn
// p0 p1 ...: the controls and the coefficients are told apart by n, in elaboration.
struct Polynomial {
  Word name, positive, negative;
  ExpressionPtr dimension;
  std::vector<Word> arguments;
};

// B: name n+ n- v=expr | i=expr   (quantity is "v" or "i")
struct Behavioral {
  Word name, positive, negative, quantity;
  ExpressionPtr expression;
};

// D: name anode cathode model [area] [off] [ic=... temp=...]
struct Diode {
  Word name, anode, cathode, model;
  std::optional<ExpressionPtr> area;
  bool off = false;
  std::vector<Assignment> parameters;
};

// M: name drain gate source bulk model [l=... w=... ad=... as=... pd=... ps=... nrd=... nrs=... m=...] [off]
struct Mosfet {
  Word name, drain, gate, source, bulk, model;
  std::vector<Assignment> parameters;
  bool off = false;
};

// S: name n+ n- nc+ nc- model [on|off]
struct VoltageSwitch {
  Word name, positive, negative, control_positive, control_negative, model;
  std::optional<Word> state;
};

// W: name n+ n- vcontrol model [on|off]
struct CurrentSwitch {
  Word name, positive, negative, control, model;
  std::optional<Word> state;
};

// X: name nodes... subcircuit [params:] [name=value...]
struct Instance {
  Word name;
  std::vector<Word> nodes;
  std::vector<Assignment> parameters;
  Word subcircuit;
};

struct ParamCard {
  std::vector<Assignment> assignments;
};

// .model name type [(] name=value... [)]
struct ModelCard {
  Word name, type;
  std::vector<Assignment> parameters;
};

// .subckt name ports... [params:] name=default... / body / .ends
struct Subcircuit {
  Word name;
  std::vector<Word> ports;
  std::vector<Assignment> parameters;
  std::vector<Card> body;
};

// .include path, or .lib path section (then only that section's cards are kept).
struct Include {
  Word directive;  // "include" or "lib"
  Word path;       // as written (case kept)
  std::optional<Word> section;
  std::vector<Card> cards;
};

// .tran tstep tstop [tstart [tmax]] [uic]
struct TranCard {
  Word directive;
  ExpressionPtr step, stop;
  std::optional<ExpressionPtr> start, max_step;
  bool uic = false;
};

// .ic / .nodeset v(node[, reference])=value ...
struct NodeAssignment {
  Word node;
  std::optional<Word> reference;
  ExpressionPtr value;
};
struct NodeValuesCard {
  Word directive;  // "ic" or "nodeset"
  std::vector<NodeAssignment> values;
};

// .options name[=value] ...: value is a number/expression or a word (method=gear).
struct OptionItem {
  Word name;
  std::optional<ExpressionPtr> number;
  std::optional<Word> word;
};
struct OptionsCard {
  Word directive;
  std::vector<OptionItem> items;
};

// .save / .print / .probe items: v(n), v(n1,n2), i(vx), or a bare word (all, or a node name).
struct OutputItem {
  Word function;  // "v", "i", or empty for a bare word
  std::vector<Word> args;
};
struct OutputCard {
  Word directive;
  std::vector<OutputItem> items;
};

// .global n1 n2 ...: nodes that subcircuits share with the top level instead of their own.
struct GlobalCard {
  Word directive;
  std::vector<Word> nodes;
};

struct TempCard {
  Word directive;
  ExpressionPtr value;
};

struct TitleCard {
  std::string text;
  SourceRange where;
};

// A card padsim does not act on: kept so that elaboration can decide whether ignoring it is
// harmless (warning) or not (error); `text` is the whole card.
struct IgnoredCard {
  Word directive;
  std::string text;
};

struct Card {
  std::variant<TwoTerminal, Coupling, IndependentSource, VoltageControlled, CurrentControlled,
               Polynomial, Behavioral, Diode, Mosfet, VoltageSwitch, CurrentSwitch, Instance, ParamCard, ModelCard,
               Subcircuit, Include, TranCard, NodeValuesCard, OptionsCard, OutputCard, TempCard, GlobalCard,
               TitleCard, IgnoredCard>
      node;
  SourceRange where;  // the card's first token
};

struct Netlist {
  std::string title;  // the first line
  SourceRange title_where;
  std::vector<Card> cards;
};

}  // namespace netlist::ast
