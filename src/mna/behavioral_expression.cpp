#include "mna/behavioral_expression.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace mna {

namespace {

using netlist::BinaryOperator;

// A short text of a subexpression, for predicate labels in the event log.
std::string describe(const netlist::Expression& e) {
  struct Visitor {
    std::string operator()(const netlist::Number& n) const {
      char text[32];
      std::snprintf(text, sizeof text, "%g", n.value);
      return text;
    }
    std::string operator()(const netlist::ParameterRef& r) const { return r.name; }
    std::string operator()(const netlist::NodeVoltage& v) const {
      return "v(" + v.node + (v.reference.empty() ? "" : "," + v.reference) + ")";
    }
    std::string operator()(const netlist::BranchCurrent& i) const { return "i(" + i.element + ")"; }
    std::string operator()(const netlist::Time&) const { return "time"; }
    std::string operator()(const netlist::Unary& u) const {
      std::string text = u.op == netlist::UnaryOperator::negate ? "-" : "!";
      return text += describe(*u.operand);
    }
    std::string operator()(const netlist::Binary& b) const {
      static const char* symbols[] = {"+", "-", "*", "/", "^", "<", "<=", ">", ">=", "==", "!=", "&&", "||"};
      // Built by appending: GCC 12 warns falsely (-Wrestrict) on "literal" + std::string.
      std::string text = "(";
      return text.append(describe(*b.left)).append(symbols[static_cast<int>(b.op)]).append(describe(*b.right)).append(")");
    }
    std::string operator()(const netlist::Conditional& c) const {
      std::string text = "(";
      return text.append(describe(*c.condition)).append("?").append(describe(*c.if_true)).append(":").append(describe(*c.if_false)).append(")");
    }
    std::string operator()(const netlist::Call& c) const {
      std::string text = c.function + "(";
      for (std::size_t k = 0; k < c.arguments.size(); ++k) text.append(k ? "," : "").append(describe(*c.arguments[k]));
      return text + ")";
    }
  };
  return std::visit(Visitor{}, e.node);
}

bool is_condition(const netlist::Expression& e) {
  if (auto* u = std::get_if<netlist::Unary>(&e.node)) return u->op == netlist::UnaryOperator::logical_not;
  if (auto* b = std::get_if<netlist::Binary>(&e.node))
    return b->op >= BinaryOperator::less && b->op <= BinaryOperator::logical_or;
  return false;
}

// ngspice's stand-ins where its B-source functions are infinite: a divisor of exactly 0 is
// PTfudge_factor (GMIN 1e-12 times 1e-20), and ln(0) = log10(0) = -1e99. Newton's first point
// (every node at 0) is often such a point.
constexpr double kZeroDivisor = 1e-32;
constexpr double kLogOfZero = -1e99;

// ngspice's power (PTpower): |x|^y, whatever y; pwr(x, y) is the signed one.
double power(double x, double y) { return std::pow(std::abs(x), y); }

}  // namespace

BehavioralExpression::BehavioralExpression(const netlist::Expression& expression, const Unknowns& unknowns,
                                           const std::string& element)
    : element_(element) {
  compile(expression, unknowns);
  values_.resize(tape_.size());
  adjoints_.resize(tape_.size());
  partials_.resize(tape_.size());
  constant_gradient_ = find_constant_gradient();
}

bool BehavioralExpression::find_constant_gradient() const {
  // What each instruction's value is in a fixed mode, from its operands'. A condition is
  // constant there: its value is the predicate's.
  enum class Kind : std::uint8_t { constant, of_time, affine, other };
  auto sum = [](Kind a, Kind b) { return std::max(a, b); };
  auto product = [](Kind a, Kind b) {
    if (a == Kind::constant || b == Kind::constant) return std::max(a, b);
    return a == Kind::of_time && b == Kind::of_time ? Kind::of_time : Kind::other;
  };
  auto function = [](Kind a, Kind b) { return std::max(a, b) <= Kind::of_time ? std::max(a, b) : Kind::other; };
  std::vector<Kind> kinds(tape_.size(), Kind::constant);
  for (std::size_t k = 0; k < tape_.size(); ++k) {
    const Instruction& in = tape_[k];
    auto operand = [&](int index) { return index >= 0 ? kinds[index] : Kind::constant; };
    const Kind a = operand(in.a), b = operand(in.b);
    switch (in.op) {
      case Op::constant: kinds[k] = Kind::constant; break;
      case Op::input: kinds[k] = Kind::affine; break;
      case Op::time: kinds[k] = Kind::of_time; break;
      case Op::negate: kinds[k] = a; break;
      case Op::add:
      case Op::subtract: kinds[k] = sum(a, b); break;
      case Op::multiply: kinds[k] = product(a, b); break;
      case Op::divide: kinds[k] = b == Kind::constant ? a : function(a, b); break;
      case Op::greater:
      case Op::logical_not:
      case Op::logical_and:
      case Op::logical_or: kinds[k] = Kind::constant; break;
      case Op::select: kinds[k] = sum(b, operand(in.c)); break;
      default: kinds[k] = function(a, b); break;  // power, exp, ..., floor, ceil, atan2
    }
  }
  return kinds.back() <= Kind::affine;
}

int BehavioralExpression::emit(Instruction instruction) {
  tape_.push_back(instruction);
  return static_cast<int>(tape_.size()) - 1;
}

int BehavioralExpression::greater(int a, int b, std::string label) {
  predicate_labels_.push_back(std::move(label));
  return emit({.op = Op::greater, .a = a, .b = b, .index = predicate_count() - 1});
}

int BehavioralExpression::input(int unknown) {
  if (unknown == ground) return constant(0);
  int position = 0;
  while (position < static_cast<int>(inputs_.size()) && inputs_[position] != unknown) ++position;
  if (position == static_cast<int>(inputs_.size())) inputs_.push_back(unknown);
  return emit({.op = Op::input, .index = position});
}

int BehavioralExpression::compile_condition(const netlist::Expression& e, const Unknowns& unknowns) {
  const int value = compile(e, unknowns);
  if (is_condition(e)) return value;
  const int zero = constant(0);
  const std::string text = describe(e);
  return emit({.op = Op::logical_or, .a = greater(value, zero, text + ">0"), .b = greater(zero, value, text + "<0")});
}

int BehavioralExpression::compile(const netlist::Expression& e, const Unknowns& unknowns) {
  auto fail = [&](const std::string& why) -> int { throw ModelError("B source '" + element_ + "': " + why); };
  auto node = [&](const std::string& name) {
    const int found = unknowns.find_node(name);
    return found != -2 ? found : fail("node '" + name + "' is not in the circuit");
  };

  if (auto* n = std::get_if<netlist::Number>(&e.node)) return constant(n->value);
  if (auto* r = std::get_if<netlist::ParameterRef>(&e.node)) return fail("unresolved parameter '" + r->name + "'");
  if (auto* v = std::get_if<netlist::NodeVoltage>(&e.node)) {
    const int a = input(node(v->node));
    if (v->reference.empty()) return a;
    return emit({.op = Op::subtract, .a = a, .b = input(node(v->reference))});
  }
  if (auto* i = std::get_if<netlist::BranchCurrent>(&e.node)) {
    if (!unknowns.has_branch(i->element)) return fail("i(" + i->element + "): no such branch current");
    return input(unknowns.branch(i->element));
  }
  if (std::holds_alternative<netlist::Time>(e.node)) return emit({.op = Op::time});
  if (auto* u = std::get_if<netlist::Unary>(&e.node)) {
    if (u->op == netlist::UnaryOperator::negate) return emit({.op = Op::negate, .a = compile(*u->operand, unknowns)});
    return emit({.op = Op::logical_not, .a = compile_condition(*u->operand, unknowns)});
  }
  if (auto* b = std::get_if<netlist::Binary>(&e.node)) {
    if (b->op == BinaryOperator::logical_and || b->op == BinaryOperator::logical_or) {
      const int l = compile_condition(*b->left, unknowns), r = compile_condition(*b->right, unknowns);
      return emit({.op = b->op == BinaryOperator::logical_and ? Op::logical_and : Op::logical_or, .a = l, .b = r});
    }
    const int l = compile(*b->left, unknowns), r = compile(*b->right, unknowns);
    const std::string lt = describe(*b->left), rt = describe(*b->right);
    switch (b->op) {
      case BinaryOperator::add: return emit({.op = Op::add, .a = l, .b = r});
      case BinaryOperator::subtract: return emit({.op = Op::subtract, .a = l, .b = r});
      case BinaryOperator::multiply: return emit({.op = Op::multiply, .a = l, .b = r});
      case BinaryOperator::divide: return emit({.op = Op::divide, .a = l, .b = r});
      case BinaryOperator::power: return emit({.op = Op::power, .a = l, .b = r});
      case BinaryOperator::greater: return greater(l, r, lt + ">" + rt);
      case BinaryOperator::less: return greater(r, l, rt + ">" + lt);
      // A predicate holds where its guard is positive: l >= r where r > l does not, so that the
      // two sides' equality (a source resting at a threshold) counts.
      case BinaryOperator::greater_equal: return emit({.op = Op::logical_not, .a = greater(r, l, rt + ">" + lt)});
      case BinaryOperator::less_equal: return emit({.op = Op::logical_not, .a = greater(l, r, lt + ">" + rt)});
      case BinaryOperator::equal:
      case BinaryOperator::not_equal: {
        const int above = greater(l, r, lt + ">" + rt), below = greater(r, l, rt + ">" + lt);
        const int differ = emit({.op = Op::logical_or, .a = above, .b = below});
        return b->op == BinaryOperator::equal ? emit({.op = Op::logical_not, .a = differ}) : differ;
      }
      default: break;
    }
  }
  if (auto* c = std::get_if<netlist::Conditional>(&e.node)) {
    const int condition = compile_condition(*c->condition, unknowns);
    return emit({.op = Op::select, .a = condition, .b = compile(*c->if_true, unknowns), .c = compile(*c->if_false, unknowns)});
  }
  const auto& call = std::get<netlist::Call>(e.node);
  std::vector<int> args;
  for (const auto& argument : call.arguments) args.push_back(compile(*argument, unknowns));
  auto arity = [&](std::size_t n) {
    if (args.size() != n) fail(call.function + "() takes " + std::to_string(n) + " arguments");
  };
  const std::string x_text = call.arguments.empty() ? "" : describe(*call.arguments[0]);
  static const std::map<std::string, Op> smooth = {
      {"exp", Op::exp},   {"ln", Op::log},   {"log", Op::log},   {"log10", Op::log10}, {"sqrt", Op::sqrt},
      {"sin", Op::sin},   {"cos", Op::cos},  {"tan", Op::tan},   {"atan", Op::atan},   {"sinh", Op::sinh},
      {"cosh", Op::cosh}, {"tanh", Op::tanh}, {"floor", Op::floor}, {"ceil", Op::ceil}};
  if (auto found = smooth.find(call.function); found != smooth.end()) {
    arity(1);
    return emit({.op = found->second, .a = args[0]});
  }
  const std::string& f = call.function;
  if (f == "atan2") return arity(2), emit({.op = Op::atan2, .a = args[0], .b = args[1]});
  if (f == "pow") return arity(2), emit({.op = Op::power, .a = args[0], .b = args[1]});
  const int zero = constant(0);
  if (f == "abs") {
    arity(1);
    return emit({.op = Op::select, .a = greater(args[0], zero, x_text + ">0"), .b = args[0],
                 .c = emit({.op = Op::negate, .a = args[0]})});
  }
  if (f == "u") return arity(1), emit({.op = Op::select, .a = greater(args[0], zero, x_text + ">0"), .b = constant(1), .c = zero});
  if (f == "uramp") return arity(1), emit({.op = Op::select, .a = greater(args[0], zero, x_text + ">0"), .b = args[0], .c = zero});
  if (f == "sgn") {
    arity(1);
    const int negative = emit({.op = Op::select, .a = greater(zero, args[0], x_text + "<0"), .b = constant(-1), .c = zero});
    return emit({.op = Op::select, .a = greater(args[0], zero, x_text + ">0"), .b = constant(1), .c = negative});
  }
  if (f == "min" || f == "max") {
    arity(2);
    const std::string y_text = describe(*call.arguments[1]);
    const int first_larger = greater(args[0], args[1], x_text + ">" + y_text);
    return f == "max" ? emit({.op = Op::select, .a = first_larger, .b = args[0], .c = args[1]})
                      : emit({.op = Op::select, .a = first_larger, .b = args[1], .c = args[0]});
  }
  if (f == "limit") {
    arity(3);
    const std::string lo = describe(*call.arguments[1]), hi = describe(*call.arguments[2]);
    const int above = emit({.op = Op::select, .a = greater(args[0], args[2], x_text + ">" + hi), .b = args[2], .c = args[0]});
    return emit({.op = Op::select, .a = greater(args[1], args[0], lo + ">" + x_text), .b = args[1], .c = above});
  }
  if (f == "pwr") {
    // sgn(x) |x|^y
    arity(2);
    const int positive = greater(args[0], zero, x_text + ">0");
    const int magnitude = emit({.op = Op::select, .a = positive, .b = args[0], .c = emit({.op = Op::negate, .a = args[0]})});
    const int raised = emit({.op = Op::power, .a = magnitude, .b = args[1]});
    return emit({.op = Op::select, .a = positive, .b = raised, .c = emit({.op = Op::negate, .a = raised})});
  }
  return fail("unknown function '" + f + "'");
}

void BehavioralExpression::forward(double t, const Vector& x, const std::uint8_t* p, double* guard_out,
                                   bool continued) const {
  past_a_guard_ = false;
  for (std::size_t k = 0; k < tape_.size(); ++k) {
    const Instruction& in = tape_[k];
    const double a = in.a >= 0 ? values_[in.a] : 0, b = in.b >= 0 ? values_[in.b] : 0;
    double value = 0;
    std::array<double, 3> d = {0, 0, 0};
    switch (in.op) {
      case Op::constant: value = in.constant; break;
      case Op::input: value = x[inputs_[in.index]]; break;
      case Op::time: value = t; break;
      case Op::negate: value = -a, d[0] = -1; break;
      case Op::add: value = a + b, d = {1, 1, 0}; break;
      case Op::subtract: value = a - b, d = {1, -1, 0}; break;
      case Op::multiply: value = a * b, d = {b, a, 0}; break;
      case Op::divide: {
        const double divisor = b != 0 ? b : kZeroDivisor;
        value = a / divisor, d = {1 / divisor, -a / (divisor * divisor), 0};
        break;
      }
      case Op::power:
        value = power(a, b);
        d[0] = a == 0 ? (b == 1 ? 1 : 0) : b * value / a;  // at 0: x^b is flat for b > 1 (b < 1: its infinite slope is left out)
        d[1] = a != 0 ? value * std::log(std::abs(a)) : 0;
        break;
      case Op::greater:
        if (p) {
          value = p[in.index];
          if ((a - b > 0) != (value != 0)) past_a_guard_ = true;
        } else {
          guard_out[in.index] = a - b;
          value = a - b > 0;
        }
        break;
      case Op::logical_not: value = a == 0; break;
      case Op::logical_and: value = a != 0 && b != 0; break;
      case Op::logical_or: value = a != 0 || b != 0; break;
      case Op::select:
        value = a != 0 ? b : values_[in.c];
        d = {0, a != 0 ? 1.0 : 0.0, a != 0 ? 0.0 : 1.0};
        break;
      case Op::exp: value = std::exp(a), d[0] = value; break;
      // At 0 their slope is infinite and left out, as x^b's for b < 1; the logarithm of 0 is
      // ngspice's -1e99 there.
      case Op::log: value = a != 0 ? std::log(a) : kLogOfZero, d[0] = a != 0 ? 1 / a : 0; break;
      case Op::log10: value = a != 0 ? std::log10(a) : kLogOfZero, d[0] = a != 0 ? 1 / (a * std::log(10.0)) : 0; break;
      case Op::sqrt:
        if (continued && a < 0) {
          value = -std::sqrt(-a), d[0] = -0.5 / value;
          break;
        }
        value = std::sqrt(a), d[0] = a != 0 ? 0.5 / value : 0;
        break;
      case Op::sin: value = std::sin(a), d[0] = std::cos(a); break;
      case Op::cos: value = std::cos(a), d[0] = -std::sin(a); break;
      case Op::tan: value = std::tan(a), d[0] = 1 + value * value; break;
      case Op::atan: value = std::atan(a), d[0] = 1 / (1 + a * a); break;
      case Op::sinh: value = std::sinh(a), d[0] = std::cosh(a); break;
      case Op::cosh: value = std::cosh(a), d[0] = std::sinh(a); break;
      case Op::tanh: value = std::tanh(a), d[0] = 1 - value * value; break;
      case Op::floor: value = std::floor(a); break;
      case Op::ceil: value = std::ceil(a); break;
      case Op::atan2: {
        value = std::atan2(a, b);
        const double r2 = a * a + b * b;
        d = {b / r2, -a / r2, 0};
        break;
      }
    }
    values_[k] = value;
    partials_[k] = d;
  }
}

double BehavioralExpression::evaluate(double t, const Vector& x, const std::uint8_t* p, double* gradient) const {
  forward(t, x, p, nullptr);
  // Past a crossed guard a mode is only ever used to locate the crossing (the event then takes
  // the other branch): there it is continued across sqrt's domain edge, so that the crossing
  // can be located where the mode's own branch reaches that edge with its guard (sqrt(abs(v))
  // of a sine: the branch v of abs reaches v < 0 as the guard v > 0 crosses).
  if (p && past_a_guard_ && !std::isfinite(values_.back())) forward(t, x, p, nullptr, true);
  const double result = values_.back();
  if (!gradient) return result;
  std::fill(gradient, gradient + inputs_.size(), 0.0);
  std::fill(adjoints_.begin(), adjoints_.end(), 0.0);
  adjoints_.back() = 1;
  for (int k = static_cast<int>(tape_.size()) - 1; k >= 0; --k) {
    const double adjoint = adjoints_[k];
    if (adjoint == 0) continue;  // dead branches may hold non-finite partials: never touch them
    const Instruction& in = tape_[k];
    if (in.op == Op::input) {
      gradient[in.index] += adjoint;
      continue;
    }
    const int operands[3] = {in.a, in.b, in.c};
    for (int j = 0; j < 3; ++j)
      if (operands[j] >= 0 && partials_[k][j] != 0) adjoints_[operands[j]] += adjoint * partials_[k][j];
  }
  return result;
}

void BehavioralExpression::guards(double t, const Vector& x, double* out) const { forward(t, x, nullptr, out); }

}  // namespace mna
