// The AST as netlist text. Values print as plain numbers or {expression}; expressions take the
// parentheses the grammar's precedence needs and no more, so that parsing the text gives the
// same AST back (positions aside) and nests no deeper than the text it came from did (a chain
// of 100 unary minus signs, each parenthesized, exceeded the parser's nesting limit).
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "netlist/netlist.hpp"

namespace netlist {

namespace {

const char* symbol(BinaryOperator op) {
  switch (op) {
    case BinaryOperator::add: return "+";
    case BinaryOperator::subtract: return "-";
    case BinaryOperator::multiply: return "*";
    case BinaryOperator::divide: return "/";
    case BinaryOperator::power: return "^";
    case BinaryOperator::less: return "<";
    case BinaryOperator::less_equal: return "<=";
    case BinaryOperator::greater: return ">";
    case BinaryOperator::greater_equal: return ">=";
    case BinaryOperator::equal: return "==";
    case BinaryOperator::not_equal: return "!=";
    case BinaryOperator::logical_and: return "&&";
    case BinaryOperator::logical_or: return "||";
  }
  return "?";
}

std::string number(double value) { return fmt::format("{}", value); }

// The grammar's levels, loosest first: an operand below the level its position asks for is
// parenthesized.
enum Level { conditional, logical_or, logical_and, equality, relational, additive, multiplicative, unary, power, primary };

Level level_of(BinaryOperator op) {
  switch (op) {
    case BinaryOperator::add:
    case BinaryOperator::subtract: return additive;
    case BinaryOperator::multiply:
    case BinaryOperator::divide: return multiplicative;
    case BinaryOperator::power: return power;
    case BinaryOperator::less:
    case BinaryOperator::less_equal:
    case BinaryOperator::greater:
    case BinaryOperator::greater_equal: return relational;
    case BinaryOperator::equal:
    case BinaryOperator::not_equal: return equality;
    case BinaryOperator::logical_and: return logical_and;
    case BinaryOperator::logical_or: return logical_or;
  }
  return primary;
}

Level level_of(const Expression& e) {
  if (auto* b = std::get_if<Binary>(&e.node)) return level_of(b->op);
  if (std::holds_alternative<Unary>(e.node)) return unary;
  if (std::holds_alternative<Conditional>(e.node)) return conditional;
  // A negative number prints with its sign, which parses as a unary minus.
  if (auto* n = std::get_if<Number>(&e.node); n && std::signbit(n->value)) return unary;
  return primary;
}

// e in a position that asks for at least `least`.
std::string print_at(const Expression& e, Level least) {
  const std::string text = print(e);
  return level_of(e) < least ? "(" + text + ")" : text;
}

// A value position: a number as is, anything else in braces.
std::string value(const ExpressionPtr& expression) {
  if (auto* n = std::get_if<Number>(&expression->node)) return number(n->value);
  return fmt::format("{{{}}}", print(*expression));
}

std::string assignments(const std::vector<ast::Assignment>& list, bool as_values) {
  std::string text;
  for (const ast::Assignment& a : list)
    text += fmt::format(" {}={}", a.name.text,
                        as_values ? value(a.value) : fmt::format("{{{}}}", print(*a.value)));
  return text;
}

struct CardPrinter {
  std::string& out;

  void line(const std::string& text) { out += text + "\n"; }

  void operator()(const ast::TwoTerminal& c) {
    line(fmt::format("{} {} {} {}{}", c.name.text, c.positive.text, c.negative.text, value(c.value),
                     assignments(c.parameters, true)));
  }
  void operator()(const ast::Coupling& c) {
    line(fmt::format("{} {} {} {}", c.name.text, c.first.text, c.second.text, value(c.value)));
  }
  void operator()(const ast::IndependentSource& c) {
    std::string text = fmt::format("{} {} {}", c.name.text, c.positive.text, c.negative.text);
    for (const ast::SourceSpec& spec : c.specs) {
      if (spec.kind.text.empty()) {
        text += fmt::format(" {}", value(spec.args[0]));
      } else if (spec.kind.text == "dc" || spec.kind.text == "ac") {
        text += fmt::format(" {}", spec.kind.text);
        for (const auto& arg : spec.args) text += fmt::format(" {}", value(arg));
      } else {
        std::vector<std::string> args;
        for (const auto& arg : spec.args) args.push_back(value(arg));
        text += fmt::format(" {}({}){}", spec.kind.text, fmt::join(args, " "),
                            assignments(spec.options, true));
      }
    }
    line(text);
  }
  void operator()(const ast::VoltageControlled& c) {
    line(fmt::format("{} {} {} {} {} {}", c.name.text, c.positive.text, c.negative.text,
                     c.control_positive.text, c.control_negative.text, value(c.gain)));
  }
  void operator()(const ast::CurrentControlled& c) {
    line(fmt::format("{} {} {} {} {}", c.name.text, c.positive.text, c.negative.text,
                     c.control.text, value(c.gain)));
  }
  void operator()(const ast::Polynomial& c) {
    std::vector<std::string> arguments;
    for (const ast::Word& word : c.arguments) arguments.push_back(word.text);
    line(fmt::format("{} {} {} poly({}) {}", c.name.text, c.positive.text, c.negative.text, value(c.dimension),
                     fmt::join(arguments, " ")));
  }
  void operator()(const ast::Behavioral& c) {
    // An E or G card written with an expression reads back as one: vol= or cur=.
    const char letter = c.name.text[0];
    const std::string quantity = letter == 'b' ? c.quantity.text : c.quantity.text == "v" ? "vol" : "cur";
    line(fmt::format("{} {} {} {}={{{}}}", c.name.text, c.positive.text, c.negative.text, quantity,
                     print(*c.expression)));
  }
  void operator()(const ast::Diode& c) {
    line(fmt::format("{} {} {} {}{}{}{}", c.name.text, c.anode.text, c.cathode.text, c.model.text,
                     c.area ? fmt::format(" {}", value(*c.area)) : "", c.off ? " off" : "",
                     assignments(c.parameters, true)));
  }
  void operator()(const ast::Mosfet& c) {
    line(fmt::format("{} {} {} {} {} {}{}{}", c.name.text, c.drain.text, c.gate.text, c.source.text, c.bulk.text,
                     c.model.text, assignments(c.parameters, true), c.off ? " off" : ""));
  }
  void operator()(const ast::VoltageSwitch& c) {
    line(fmt::format("{} {} {} {} {} {}{}", c.name.text, c.positive.text, c.negative.text,
                     c.control_positive.text, c.control_negative.text, c.model.text,
                     c.state ? fmt::format(" {}", c.state->text) : ""));
  }
  void operator()(const ast::CurrentSwitch& c) {
    line(fmt::format("{} {} {} {} {}{}", c.name.text, c.positive.text, c.negative.text,
                     c.control.text, c.model.text, c.state ? fmt::format(" {}", c.state->text) : ""));
  }
  void operator()(const ast::Instance& c) {
    std::string text = c.name.text;
    for (const ast::Word& node : c.nodes) text += " " + node.text;
    text += " " + c.subcircuit.text;
    if (!c.parameters.empty()) text += fmt::format(" params:{}", assignments(c.parameters, false));
    line(text);
  }
  void operator()(const ast::ParamCard& c) { line(".param" + assignments(c.assignments, false)); }
  void operator()(const ast::ModelCard& c) {
    line(fmt::format(".model {} {}({})", c.name.text, c.type.text,
                     assignments(c.parameters, true).substr(c.parameters.empty() ? 0 : 1)));
  }
  void operator()(const ast::Subcircuit& c) {
    std::string text = ".subckt " + c.name.text;
    for (const ast::Word& port : c.ports) text += " " + port.text;
    if (!c.parameters.empty()) text += fmt::format(" params:{}", assignments(c.parameters, false));
    line(text);
    for (const ast::Card& card : c.body) std::visit(*this, card.node);
    line(".ends " + c.name.text);
  }
  void operator()(const ast::Include& c) {
    line(fmt::format(".{} \"{}\"{}", c.directive.text, c.path.text,
                     c.section ? fmt::format(" {}", c.section->text) : ""));
  }
  void operator()(const ast::TranCard& c) {
    line(fmt::format(".tran {} {}{}{}{}", value(c.step), value(c.stop),
                     c.start ? fmt::format(" {}", value(*c.start)) : "", c.max_step ? fmt::format(" {}", value(*c.max_step)) : "",
                     c.uic ? " uic" : ""));
  }
  void operator()(const ast::NodeValuesCard& c) {
    std::string text = "." + c.directive.text;
    for (const ast::NodeAssignment& a : c.values)
      text += fmt::format(" v({}{})={}", a.node.text, a.reference ? fmt::format(",{}", a.reference->text) : "",
                          value(a.value));
    line(text);
  }
  void operator()(const ast::OptionsCard& c) {
    std::string text = ".options";
    for (const ast::OptionItem& item : c.items) {
      text += fmt::format(" {}", item.name.text);
      if (item.number) text += fmt::format("={}", value(*item.number));
      if (item.word) text += fmt::format("={}", item.word->text);
    }
    line(text);
  }
  void operator()(const ast::OutputCard& c) {
    std::string text = "." + c.directive.text;
    for (const ast::OutputItem& item : c.items) {
      if (item.function.text.empty()) {
        text += fmt::format(" {}", item.args[0].text);
        continue;
      }
      std::vector<std::string> args;
      for (const ast::Word& arg : item.args) args.push_back(arg.text);
      text += fmt::format(" {}({})", item.function.text, fmt::join(args, ","));
    }
    line(text);
  }
  void operator()(const ast::TempCard& c) { line(".temp " + value(c.value)); }
  void operator()(const ast::GlobalCard& c) {
    std::string text = ".global";
    for (const ast::Word& node : c.nodes) text += " " + node.text;
    line(text);
  }
  void operator()(const ast::TitleCard& c) { line(".title " + c.text); }
  void operator()(const ast::IgnoredCard& c) { line(c.text); }
};

struct ExpressionPrinter {
  std::string operator()(const Number& n) const { return number(n.value); }
  std::string operator()(const ParameterRef& r) const { return r.name; }
  std::string operator()(const NodeVoltage& v) const {
    return v.reference.empty() ? fmt::format("v({})", v.node)
                               : fmt::format("v({},{})", v.node, v.reference);
  }
  std::string operator()(const BranchCurrent& i) const { return fmt::format("i({})", i.element); }
  std::string operator()(const Time&) const { return "time"; }
  std::string operator()(const Unary& u) const {
    return fmt::format("{}{}", u.op == UnaryOperator::negate ? "-" : "!", print_at(*u.operand, unary));
  }
  // Each level takes its own level on the left (left-associative) and the next on the right;
  // power's right is an exponent, as the grammar has it: a primary or a signed operand.
  std::string operator()(const Binary& b) const {
    const Level level = level_of(b.op);
    if (level == power) {
      const Level exponent = level_of(*b.right);
      const std::string right = print(*b.right);
      if (exponent != unary && exponent != primary) return fmt::format("{} {} ({})", print_at(*b.left, power), symbol(b.op), right);
      return fmt::format("{} {} {}", print_at(*b.left, power), symbol(b.op), right);
    }
    return fmt::format("{} {} {}", print_at(*b.left, level), symbol(b.op), print_at(*b.right, static_cast<Level>(level + 1)));
  }
  std::string operator()(const Conditional& c) const {
    return fmt::format("{} ? {} : {}", print_at(*c.condition, logical_or), print(*c.if_true), print(*c.if_false));
  }
  std::string operator()(const Call& c) const {
    std::vector<std::string> arguments;
    for (const auto& argument : c.arguments) arguments.push_back(print(*argument));
    return fmt::format("{}({})", c.function, fmt::join(arguments, ", "));
  }
};

}  // namespace

std::string print(const Expression& expression) {
  return std::visit(ExpressionPrinter{}, expression.node);
}

std::string print(const ast::Netlist& netlist) {
  std::string out = fmt::format("{}\n", netlist.title);
  CardPrinter printer{out};
  for (const ast::Card& card : netlist.cards) std::visit(printer, card.node);
  out += ".end\n";
  return out;
}

}  // namespace netlist
