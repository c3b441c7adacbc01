// Elaboration: AST -> FlatCircuit. The subcircuit hierarchy is checked first (recursion, depth,
// the number of cards it expands to) without building anything; then parameters are
// evaluated in dependency order, subcircuits expanded with hierarchical names, references
// (models, controlling sources, inductors) checked.
//
// Which ignored cards are errors: an analysis padsim does not run (.ac .dc .op .noise ...) is
// only a warning when the netlist has a .tran (the transient result is what was asked for);
// without a .tran it is an error. Output-only cards (.plot .four .meas ...) and unknown dot
// cards are warnings. Cards that would change the circuit (.func .if ...) were
// rejected by the parser.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "netlist/netlist.hpp"

namespace netlist {

namespace {

constexpr std::size_t max_subcircuit_depth = 100;

bool is_one_of(const std::string& name, std::initializer_list<const char*> names) {
  for (const char* candidate : names)
    if (name == candidate) return true;
  return false;
}

std::string count(std::size_t n, const std::string& noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

bool truthy(double value) { return value != 0.0; }

double apply_function(const std::string& name, const std::vector<double>& a) {
  if (name == "exp") return std::exp(a[0]);
  if (name == "ln" || name == "log") return std::log(a[0]);  // ngspice: log is natural
  if (name == "log10") return std::log10(a[0]);
  if (name == "sqrt") return std::sqrt(a[0]);
  if (name == "sin") return std::sin(a[0]);
  if (name == "cos") return std::cos(a[0]);
  if (name == "tan") return std::tan(a[0]);
  if (name == "atan") return std::atan(a[0]);
  if (name == "atan2") return std::atan2(a[0], a[1]);
  if (name == "sinh") return std::sinh(a[0]);
  if (name == "cosh") return std::cosh(a[0]);
  if (name == "tanh") return std::tanh(a[0]);
  if (name == "abs") return std::fabs(a[0]);
  if (name == "min") return std::fmin(a[0], a[1]);
  if (name == "max") return std::fmax(a[0], a[1]);
  if (name == "pow") return std::pow(a[0], a[1]);
  if (name == "pwr") return std::copysign(std::pow(std::fabs(a[0]), a[1]), a[0]);
  if (name == "sgn") return a[0] > 0 ? 1.0 : a[0] < 0 ? -1.0 : 0.0;
  if (name == "u") return a[0] > 0 ? 1.0 : 0.0;
  if (name == "uramp") return a[0] > 0 ? a[0] : 0.0;
  if (name == "limit") return std::fmin(std::fmax(a[0], a[1]), a[2]);
  if (name == "floor") return std::floor(a[0]);
  if (name == "ceil") return std::ceil(a[0]);
  return std::nan("");  // the parser admits only the functions above
}

double apply_binary(BinaryOperator op, double l, double r) {
  switch (op) {
    case BinaryOperator::add: return l + r;
    case BinaryOperator::subtract: return l - r;
    case BinaryOperator::multiply: return l * r;
    case BinaryOperator::divide: return l / r;
    case BinaryOperator::power: return std::pow(l, r);
    case BinaryOperator::less: return l < r;
    case BinaryOperator::less_equal: return l <= r;
    case BinaryOperator::greater: return l > r;
    case BinaryOperator::greater_equal: return l >= r;
    case BinaryOperator::equal: return l == r;
    case BinaryOperator::not_equal: return l != r;
    case BinaryOperator::logical_and: return truthy(l) && truthy(r);
    case BinaryOperator::logical_or: return truthy(l) || truthy(r);
  }
  return std::nan("");
}

std::size_t saturating_add(std::size_t a, std::size_t b) {
  return a > std::numeric_limits<std::size_t>::max() - b ? std::numeric_limits<std::size_t>::max()
                                                         : a + b;
}

// The cards of a body with the cards of its includes in their place.
void flatten_includes(const std::vector<ast::Card>& cards, std::vector<const ast::Card*>& out) {
  for (const ast::Card& card : cards) {
    if (auto* include = std::get_if<ast::Include>(&card.node))
      flatten_includes(include->cards, out);
    else
      out.push_back(&card);
  }
}

// Parameter values of one subcircuit instance (or the top level), falling back to the
// enclosing instance's.
struct Scope {
  const Scope* parent = nullptr;
  std::unordered_map<std::string, double> values;

  const double* find(const std::string& name) const {
    for (const Scope* scope = this; scope; scope = scope->parent) {
      auto found = scope->values.find(name);
      if (found != scope->values.end()) return &found->second;
    }
    return nullptr;
  }
};

// Subcircuits and models defined in one body, falling back to the enclosing body's.
struct Definitions {
  const Definitions* parent = nullptr;
  std::string prefix;  // of the instance whose body this is: models defined here get it
  std::unordered_map<std::string, const ast::Subcircuit*> subcircuits;
  std::unordered_map<std::string, const ast::ModelCard*> models;

  const ast::Subcircuit* find_subcircuit(const std::string& name) const {
    for (const Definitions* d = this; d; d = d->parent)
      if (auto found = d->subcircuits.find(name); found != d->subcircuits.end()) return found->second;
    return nullptr;
  }
  // The model card and the flat name of the model it became.
  std::pair<const ast::ModelCard*, std::string> find_model(const std::string& name) const {
    for (const Definitions* d = this; d; d = d->parent)
      if (auto found = d->models.find(name); found != d->models.end())
        return {found->second, d->prefix + name};
    return {nullptr, ""};
  }
};

// Registers the subcircuits defined in a body (its cards); a second one of a name is an error, as
// is a port named twice (which of the instance's nodes it is would be arbitrary).
void define_subcircuits(const std::vector<const ast::Card*>& cards, Definitions& definitions,
                        Diagnostics& diagnostics) {
  for (const ast::Card* card : cards)
    if (auto* subcircuit = std::get_if<ast::Subcircuit>(&card->node)) {
      if (!definitions.subcircuits.emplace(subcircuit->name.text, subcircuit).second)
        diagnostics.error(subcircuit->name.where,
                          "subcircuit '" + subcircuit->name.text + "' is defined twice");
      const std::vector<ast::Word>& ports = subcircuit->ports;
      for (auto port = ports.begin(); port != ports.end(); ++port)
        if (std::any_of(ports.begin(), port, [&](const ast::Word& earlier) { return earlier.text == port->text; }))
          diagnostics.error(port->where,
                            "port '" + port->text + "' of subcircuit '" + subcircuit->name.text + "' is named twice");
    }
}

// The subcircuit hierarchy, checked before elaboration builds anything: an instance of a subcircuit
// being expanded (recursion), nesting deeper than max_subcircuit_depth, and more cards than the
// limit. Elaboration visits every card of a body once per instance of it, and those visits are
// counted: an X card is one plus its subcircuit's cards, and empty subcircuits, or bodies of only
// models or parameters, count too. Subcircuits instantiating subcircuits multiply (ten levels of
// ten instances are 10^10 cards), so the cards are counted once per subcircuit definition
// (saturating) and per scope its names resolve in: a subcircuit defined inside a body is seen by
// the bodies that body's instances expand.
class Hierarchy {
 public:
  Hierarchy(Diagnostics& diagnostics, std::size_t max_cards)
      : diagnostics_(diagnostics), max_cards_(max_cards) {}

  // True if the top-level cards may be elaborated; otherwise an error was reported.
  bool check(const std::vector<const ast::Card*>& cards) {
    Definitions top;
    define_subcircuits(cards, top, diagnostics_);
    std::vector<std::string> chain;
    const ast::Card* over_limit = nullptr;
    if (!walk(cards, top, chain, &over_limit)) return false;
    if (!over_limit) return true;
    diagnostics_.error(over_limit->where,
                       "the circuit expands to more than " + std::to_string(max_cards_) +
                           " cards (each subcircuit instance counts, with its body's cards)");
    return false;
  }

 private:
  struct Expansion {
    std::size_t cards = 0;  // saturating
    std::size_t depth = 0;  // levels of subcircuit bodies below this one
  };

  // The expansion of a body; nullopt if recursion or too deep nesting was reported. `chain` are
  // the subcircuits being expanded, outermost first. `over_limit` (the top level) gets the first
  // card at which the running count exceeds the limit.
  std::optional<Expansion> walk(const std::vector<const ast::Card*>& cards,
                                const Definitions& definitions, std::vector<std::string>& chain,
                                const ast::Card** over_limit = nullptr) {
    Expansion total;
    for (const ast::Card* card : cards) {
      std::size_t expanded = 1;
      if (auto* instance = std::get_if<ast::Instance>(&card->node)) {
        const ast::Subcircuit* subcircuit = definitions.find_subcircuit(instance->subcircuit.text);
        if (!subcircuit) continue;  // elaboration reports it
        auto inner = expand(*instance, *subcircuit, definitions, chain);
        if (!inner) return std::nullopt;
        expanded = saturating_add(expanded, inner->cards);
        total.depth = std::max(total.depth, inner->depth + 1);
      }
      total.cards = saturating_add(total.cards, expanded);
      if (over_limit && !*over_limit && total.cards > max_cards_) *over_limit = card;
    }
    return total;
  }

  // The expansion of one X card's subcircuit, whose instance sees `enclosing`.
  std::optional<Expansion> expand(const ast::Instance& card, const ast::Subcircuit& subcircuit,
                                  const Definitions& enclosing, std::vector<std::string>& chain) {
    if (std::find(chain.begin(), chain.end(), subcircuit.name.text) != chain.end()) {
      diagnostics_.error(card.subcircuit.where,
                         "subcircuit '" + subcircuit.name.text + "' instantiates itself");
      return std::nullopt;
    }
    if (chain.size() >= max_subcircuit_depth) {
      diagnostics_.error(card.subcircuit.where, "subcircuits nest more than " +
                                                    std::to_string(max_subcircuit_depth) +
                                                    " levels deep");
      return std::nullopt;
    }
    // A count from another place in the hierarchy holds here unless this place is deeper and
    // the walk must find where the nesting exceeds the depth.
    std::pair key{&subcircuit, &enclosing};
    if (auto known = expansions_.find(key);
        known != expansions_.end() && chain.size() + known->second.depth < max_subcircuit_depth)
      return known->second;
    std::vector<const ast::Card*> cards;
    flatten_includes(subcircuit.body, cards);
    chain.push_back(subcircuit.name.text);
    auto expansion = walk(cards, scope(subcircuit, cards, enclosing), chain);
    chain.pop_back();
    if (expansion) expansions_[key] = *expansion;
    return expansion;
  }

  // What the names in a subcircuit's body resolve to: its own subcircuits, then `enclosing`.
  // Bodies defining none share `enclosing`, so that counts are shared as widely as possible.
  const Definitions& scope(const ast::Subcircuit& subcircuit,
                           const std::vector<const ast::Card*>& cards,
                           const Definitions& enclosing) {
    if (std::none_of(cards.begin(), cards.end(), [](const ast::Card* card) {
          return std::holds_alternative<ast::Subcircuit>(card->node);
        }))
      return enclosing;
    std::unique_ptr<Definitions>& own = scopes_[{&subcircuit, &enclosing}];
    if (!own) {
      own = std::make_unique<Definitions>(Definitions{&enclosing, "", {}, {}});
      define_subcircuits(cards, *own, diagnostics_);
    }
    return *own;
  }

  using Key = std::pair<const ast::Subcircuit*, const Definitions*>;
  Diagnostics& diagnostics_;
  std::size_t max_cards_;
  std::map<Key, Expansion> expansions_;
  std::map<Key, std::unique_ptr<Definitions>> scopes_;
};

// Where the cards of one body (top level or an instance's subcircuit) go in the flat circuit.
struct Instance {
  std::string prefix;                                 // "" or "x1." or "x1.x2."
  std::unordered_map<std::string, std::string> ports;  // subcircuit port -> connected node
  const Scope* scope;
  const Definitions* definitions;
  const std::set<std::string>* global_nodes = nullptr;  // .global nodes, not the instance's own (set for each)

  std::string node(const std::string& name) const {
    if (name == "0" || name == "gnd") return "0";
    if (auto port = ports.find(name); port != ports.end()) return port->second;
    if (global_nodes->contains(name)) return name;
    return prefix + name;
  }
  std::string element(const std::string& name) const { return prefix + name; }
};

class Elaborator {
 public:
  Elaborator(Diagnostics& diagnostics, std::size_t max_cards)
      : diagnostics_(diagnostics), max_cards_(max_cards) {}

  std::optional<FlatCircuit> run(const ast::Netlist& netlist) {
    int errors_before = diagnostics_.error_count();
    circuit_.title = netlist.title;
    std::vector<const ast::Card*> cards;
    flatten_includes(netlist.cards, cards);
    has_tran_ = std::any_of(cards.begin(), cards.end(), [](const ast::Card* card) {
      return std::holds_alternative<ast::TranCard>(card->node);
    });
    if (!Hierarchy(diagnostics_, max_cards_).check(cards)) return std::nullopt;
    Scope global;
    Definitions definitions;
    // Global nodes hold for every instance, wherever the .global card stands at the top level.
    for (const ast::Card* card : cards)
      if (const auto* globals = std::get_if<ast::GlobalCard>(&card->node))
        for (const ast::Word& node : globals->nodes) global_nodes_.insert(node.text);
    Instance top{"", {}, &global, &definitions, &global_nodes_};
    elaborate_body(cards, top, global, definitions);
    check_references();
    for (const Diagnostic& diagnostic : diagnostics_.all())
      if (diagnostic.severity != Severity::error) circuit_.warnings.push_back(diagnostic);
    if (diagnostics_.error_count() > errors_before) return std::nullopt;
    return std::move(circuit_);
  }

 private:
  // ---- expressions ------------------------------------------------------------------------

  std::optional<double> evaluate(const Expression& expression, const Scope& scope) {
    return std::visit(
        [&](const auto& node) -> std::optional<double> { return evaluate_node(node, expression, scope); },
        expression.node);
  }

  std::optional<double> evaluate_node(const Number& number, const Expression&, const Scope&) {
    return number.value;
  }
  std::optional<double> evaluate_node(const ParameterRef& ref, const Expression& e, const Scope& scope) {
    if (const double* value = scope.find(ref.name)) return *value;
    if (ref.name == "pi") return std::numbers::pi;
    diagnostics_.error(e.where, "parameter '" + ref.name + "' is not defined");
    return std::nullopt;
  }
  std::optional<double> evaluate_node(const NodeVoltage&, const Expression& e, const Scope&) {
    diagnostics_.error(e.where, "a node voltage is only allowed in a B source expression");
    return std::nullopt;
  }
  std::optional<double> evaluate_node(const BranchCurrent&, const Expression& e, const Scope&) {
    diagnostics_.error(e.where, "a branch current is only allowed in a B source expression");
    return std::nullopt;
  }
  std::optional<double> evaluate_node(const Time&, const Expression& e, const Scope&) {
    diagnostics_.error(e.where, "time is only allowed in a B source expression");
    return std::nullopt;
  }
  std::optional<double> evaluate_node(const Unary& unary, const Expression&, const Scope& scope) {
    auto operand = evaluate(*unary.operand, scope);
    if (!operand) return std::nullopt;
    return unary.op == UnaryOperator::negate ? -*operand : double(!truthy(*operand));
  }
  std::optional<double> evaluate_node(const Binary& binary, const Expression&, const Scope& scope) {
    auto left = evaluate(*binary.left, scope);
    auto right = evaluate(*binary.right, scope);
    if (!left || !right) return std::nullopt;
    return apply_binary(binary.op, *left, *right);
  }
  std::optional<double> evaluate_node(const Conditional& c, const Expression&, const Scope& scope) {
    auto condition = evaluate(*c.condition, scope);
    if (!condition) return std::nullopt;
    return evaluate(truthy(*condition) ? *c.if_true : *c.if_false, scope);
  }
  std::optional<double> evaluate_node(const Call& call, const Expression&, const Scope& scope) {
    std::vector<double> arguments;
    for (const ExpressionPtr& argument : call.arguments) {
      auto value = evaluate(*argument, scope);
      if (!value) return std::nullopt;
      arguments.push_back(*value);
    }
    return apply_function(call.function, arguments);
  }

  // A value that must be a finite number.
  std::optional<double> value(const ExpressionPtr& expression, const Scope& scope) {
    if (auto* number = std::get_if<Number>(&expression->node)) return number->value;
    auto result = evaluate(*expression, scope);
    if (result && !std::isfinite(*result)) {
      diagnostics_.error(expression->where, "the value is not a finite number");
      return std::nullopt;
    }
    return result;
  }

  // A B-source expression with parameters replaced by their values and names made
  // hierarchical.
  ExpressionPtr substitute(const ExpressionPtr& expression, const Instance& instance) {
    auto make = [&](decltype(Expression::node) node) {
      return std::make_shared<const Expression>(Expression{std::move(node), expression->where});
    };
    const auto& node = expression->node;
    if (std::holds_alternative<ParameterRef>(node)) {
      auto result = evaluate(*expression, *instance.scope);
      return result ? make(Number{*result}) : nullptr;
    }
    if (auto* voltage = std::get_if<NodeVoltage>(&node))
      return make(NodeVoltage{instance.node(voltage->node),
                              voltage->reference.empty() ? "" : instance.node(voltage->reference)});
    if (auto* current = std::get_if<BranchCurrent>(&node)) {
      branch_current_uses_.push_back({instance.element(current->element), expression->where});
      return make(BranchCurrent{instance.element(current->element)});
    }
    if (auto* unary = std::get_if<Unary>(&node)) {
      auto operand = substitute(unary->operand, instance);
      return operand ? make(Unary{unary->op, operand}) : nullptr;
    }
    if (auto* binary = std::get_if<Binary>(&node)) {
      auto left = substitute(binary->left, instance);
      auto right = substitute(binary->right, instance);
      return left && right ? make(Binary{binary->op, left, right}) : nullptr;
    }
    if (auto* conditional = std::get_if<Conditional>(&node)) {
      auto condition = substitute(conditional->condition, instance);
      auto if_true = substitute(conditional->if_true, instance);
      auto if_false = substitute(conditional->if_false, instance);
      return condition && if_true && if_false ? make(Conditional{condition, if_true, if_false})
                                              : nullptr;
    }
    if (auto* call = std::get_if<Call>(&node)) {
      Call result{call->function, {}};
      for (const ExpressionPtr& argument : call->arguments) {
        result.arguments.push_back(substitute(argument, instance));
        if (!result.arguments.back()) return nullptr;
      }
      return make(std::move(result));
    }
    return expression;  // Number, Time
  }

  // ---- parameters -------------------------------------------------------------------------

  struct PendingParameter {
    ExpressionPtr expression;
    SourceRange where;
    enum { pending, evaluating, done } state = pending;
  };

  // Evaluates `definitions` into `scope` in dependency order; a cycle is an error naming it.
  void evaluate_parameters(std::vector<std::pair<ast::Word, ExpressionPtr>> const& definitions,
                           Scope& scope) {
    std::unordered_map<std::string, PendingParameter> pending;
    std::vector<std::string> order;
    for (const auto& [name, expression] : definitions) {
      if (auto existing = pending.find(name.text); existing != pending.end()) {
        diagnostics_.warning(name.where, "parameter '" + name.text + "' is defined again; this "
                                         "definition replaces the earlier one");
        existing->second = {expression, name.where};
        continue;
      }
      pending.emplace(name.text, PendingParameter{expression, name.where});
      order.push_back(name.text);
    }
    std::vector<std::string> stack;
    std::function<bool(const std::string&)> resolve = [&](const std::string& name) -> bool {
      PendingParameter& parameter = pending.at(name);
      if (parameter.state == PendingParameter::done) return scope.values.count(name) > 0;
      if (parameter.state == PendingParameter::evaluating) {
        std::string cycle;
        auto start = std::find(stack.begin(), stack.end(), name);
        for (auto it = start; it != stack.end(); ++it) cycle += *it + " -> ";
        diagnostics_.error(pending.at(*start).where, "parameter cycle: " + cycle + name);
        return false;
      }
      parameter.state = PendingParameter::evaluating;
      stack.push_back(name);
      bool dependencies_resolved = true;
      visit_references(*parameter.expression, [&](const std::string& reference) {
        if (pending.count(reference) && !resolve(reference)) dependencies_resolved = false;
      });
      stack.pop_back();
      parameter.state = PendingParameter::done;
      if (!dependencies_resolved) return false;
      auto result = value(parameter.expression, scope);
      if (!result) return false;
      scope.values[name] = *result;
      return true;
    };
    for (const std::string& name : order) resolve(name);
  }

  template <typename Visitor>
  static void visit_references(const Expression& expression, Visitor&& visitor) {
    std::visit(
        [&](const auto& node) {
          using Node = std::decay_t<decltype(node)>;
          if constexpr (std::is_same_v<Node, ParameterRef>) {
            visitor(node.name);
          } else if constexpr (std::is_same_v<Node, Unary>) {
            visit_references(*node.operand, visitor);
          } else if constexpr (std::is_same_v<Node, Binary>) {
            visit_references(*node.left, visitor);
            visit_references(*node.right, visitor);
          } else if constexpr (std::is_same_v<Node, Conditional>) {
            visit_references(*node.condition, visitor);
            visit_references(*node.if_true, visitor);
            visit_references(*node.if_false, visitor);
          } else if constexpr (std::is_same_v<Node, Call>) {
            for (const auto& argument : node.arguments) visit_references(*argument, visitor);
          }
        },
        expression.node);
  }

  // ---- bodies -----------------------------------------------------------------------------

  void elaborate_body(const std::vector<const ast::Card*>& cards, const Instance& instance,
                      Scope& scope, Definitions& definitions) {
    define_subcircuits(cards, definitions, diagnostics_);
    std::vector<std::pair<ast::Word, ExpressionPtr>> parameters;
    for (const ast::Card* card : cards) {
      if (auto* model = std::get_if<ast::ModelCard>(&card->node)) {
        bool inserted = definitions.models.emplace(model->name.text, model).second;
        if (!inserted)
          diagnostics_.error(model->name.where, "model '" + model->name.text + "' is defined twice");
      } else if (auto* param = std::get_if<ast::ParamCard>(&card->node)) {
        for (const ast::Assignment& assignment : param->assignments)
          parameters.emplace_back(assignment.name, assignment.value);
      }
    }
    evaluate_parameters(parameters, scope);
    for (const ast::Card* card : cards)  // in netlist order; a duplicate was reported above
      if (auto* model = std::get_if<ast::ModelCard>(&card->node);
          model && definitions.models.at(model->name.text) == model)
        elaborate_model(*model, instance);
    for (const ast::Card* card : cards)
      std::visit([&](const auto& node) { elaborate_card(node, *card, instance); }, card->node);
  }

  void elaborate_model(const ast::ModelCard& card, const Instance& instance) {
    // ngspice's level-1 MOSFET parameters; UO, NSUB, NSS, TPG act only with TOX, KF and AF only
    // in noise analysis.
    static const std::vector<std::string> mosfet_parameters = {
        "level", "vto", "vt0", "kp",   "gamma", "phi", "lambda", "rd",  "rs",  "cbd", "cbs", "is",  "pb",  "cgso",
        "cgdo",  "cgbo", "rsh", "cj",  "mj",    "cjsw", "mjsw",  "js",  "tox", "ld",  "uo",  "u0",  "fc",  "nsub",
        "nss",   "tpg", "kf",  "af",   "tnom"};
    static const std::map<std::string, std::pair<ModelType, std::vector<std::string>>> known = {
        {"d",
         {ModelType::diode,
          {"is", "n", "rs", "cjo", "cj0", "vj", "m", "tt", "bv", "ibv", "nbv", "eg", "xti", "fc", "ideal",
           "ron", "roff", "vfwd"}}},
        {"sw", {ModelType::voltage_switch, {"vt", "vh", "ron", "roff", "ideal"}}},
        {"csw", {ModelType::current_switch, {"it", "ih", "ron", "roff", "ideal"}}},
        {"nmos", {ModelType::nmos, mosfet_parameters}},
        {"pmos", {ModelType::pmos, mosfet_parameters}},
    };
    auto type = known.find(card.type.text);
    if (type == known.end()) {
      diagnostics_.warning(card.type.where, "model type '" + card.type.text +
                                                  "' is not supported by padsim; model '" +
                                                  card.name.text + "' is ignored");
      return;
    }
    FlatModel model{instance.prefix + card.name.text, type->second.first, {}, card.name.where};
    const auto& names = type->second.second;
    for (const ast::Assignment& parameter : card.parameters) {
      if (std::find(names.begin(), names.end(), parameter.name.text) == names.end())
        diagnostics_.warning(parameter.name.where, "unknown " + card.type.text + " model parameter '" +
                                                       parameter.name.text + "' is kept but unused");
      if (auto v = value(parameter.value, *instance.scope))
        model.parameters[parameter.name.text] = {*v, parameter.name.where};
    }
    if (model.type == ModelType::nmos || model.type == ModelType::pmos) check_mosfet_model(model);
    circuit_.models.push_back(std::move(model));
  }

  // What padsim's MOSFET is: ngspice's level 1 at the nominal temperature, without the Meyer
  // gate capacitances (which TOX switches on there, and which are no charge: ngspice integrates
  // capacitances averaged over the step).
  void check_mosfet_model(const FlatModel& model) {
    auto refuse_unless = [&](const char* name, double supported, const char* why) {
      const auto found = model.parameters.find(name);
      if (found != model.parameters.end() && found->second.value != supported)
        diagnostics_.error(found->second.where, fmt::format("model '{}': {}", model.name, why));
    };
    refuse_unless("level", 1, "only LEVEL=1 is supported (ngspice's level-1 MOSFET)");
    refuse_unless("tox", 0,
                  "TOX (the Meyer gate capacitances) is not supported; give KP, and the gate capacitances as "
                  "CGSO, CGDO, CGBO");
    refuse_unless("tnom", 27, "TNOM other than 27 C is not supported");
  }

  FlatElement element_of(ElementKind kind, const ast::Word& name, const Instance& instance) {
    FlatElement element;
    element.kind = kind;
    element.name = instance.element(name.text);
    element.where = name.where;
    return element;
  }

  void add(FlatElement element) {
    auto [existing, inserted] = element_index_.emplace(element.name, circuit_.elements.size());
    if (!inserted) {
      diagnostics_.error(element.where, "element '" + element.name + "' is defined twice");
      diagnostics_.note(circuit_.elements[existing->second].where, "first defined here");
      return;
    }
    circuit_.elements.push_back(std::move(element));
  }

  // Instance parameters an element accepts (name -> stored where).
  void element_parameters(const std::vector<ast::Assignment>& parameters, FlatElement& element,
                          const char* kind_name, const Instance& instance) {
    for (const ast::Assignment& parameter : parameters) {
      if (parameter.name.text == "ic" && element.kind != ElementKind::resistor) {
        if (element.initial_condition) {  // which one was meant? (as a second DC value)
          diagnostics_.error(parameter.name.where, "a second IC= for " + element.name);
          continue;
        }
        element.initial_condition = value(parameter.value, *instance.scope);
        continue;
      }
      diagnostics_.error(parameter.name.where, "unknown parameter '" + parameter.name.text +
                                                   "' for " + kind_name + " " + element.name);
    }
  }

  void elaborate_card(const ast::TwoTerminal& card, const ast::Card&, const Instance& instance) {
    char letter = card.name.text[0];
    ElementKind kind = letter == 'r' ? ElementKind::resistor
                       : letter == 'c' ? ElementKind::capacitor
                                       : ElementKind::inductor;
    const char* kind_name = letter == 'r' ? "resistor" : letter == 'c' ? "capacitor" : "inductor";
    FlatElement element = element_of(kind, card.name, instance);
    element.nodes = {instance.node(card.positive.text), instance.node(card.negative.text)};
    auto v = value(card.value, *instance.scope);
    if (!v) return;
    element.value = *v;
    // Valid equations (ngspice takes it without a word), but rarely meant: with a resistor, the
    // RC mode grows as exp(t / (R |C|)) instead of decaying.
    if (kind == ElementKind::capacitor && element.value < 0)
      diagnostics_.warning(card.value->where,
                           fmt::format("capacitor {} has negative capacitance {:g} F: it stores negative energy, and "
                                       "a mode it dominates grows instead of decaying",
                                       element.name, element.value));
    element_parameters(card.parameters, element, kind_name, instance);
    add(std::move(element));
  }

  void elaborate_card(const ast::Coupling& card, const ast::Card&, const Instance& instance) {
    FlatElement element = element_of(ElementKind::coupling, card.name, instance);
    element.controls = {instance.element(card.first.text), instance.element(card.second.text)};
    auto v = value(card.value, *instance.scope);
    if (!v) return;
    element.value = *v;
    control_uses_.push_back({element.controls[0], 'l', card.first.where});
    control_uses_.push_back({element.controls[1], 'l', card.second.where});
    add(std::move(element));
  }

  void elaborate_card(const ast::IndependentSource& card, const ast::Card&, const Instance& instance) {
    ElementKind kind =
        card.name.text[0] == 'v' ? ElementKind::voltage_source : ElementKind::current_source;
    FlatElement element = element_of(kind, card.name, instance);
    element.nodes = {instance.node(card.positive.text), instance.node(card.negative.text)};
    bool valid = true;
    for (const ast::SourceSpec& spec : card.specs) {
      const std::string& spec_kind = spec.kind.text;
      if (spec_kind == "ac") continue;  // accepted and ignored: padsim runs no AC analysis
      std::vector<double> args;
      for (const ExpressionPtr& arg : spec.args) {
        auto v = value(arg, *instance.scope);
        if (!v) valid = false;
        args.push_back(v.value_or(0.0));
      }
      if (spec_kind.empty() || spec_kind == "dc") {
        element.source.dc = args.at(0);
        continue;
      }
      Waveform waveform{spec_kind == "pulse" ? WaveformKind::pulse
                        : spec_kind == "sin" ? WaveformKind::sin
                        : spec_kind == "exp" ? WaveformKind::exp
                        : spec_kind == "sffm" ? WaveformKind::sffm
                                             : WaveformKind::pwl,
                        std::move(args), std::nullopt, std::nullopt, spec.kind.where};
      for (const ast::Assignment& option : spec.options) {
        auto v = value(option.value, *instance.scope);
        if (!v) valid = false;
        (option.name.text == "r" ? waveform.repeat_from : waveform.delay) = v;
      }
      if (valid && waveform.kind == WaveformKind::pwl) valid = check_pwl(waveform, spec);
      if (valid && waveform.kind == WaveformKind::pulse) valid = check_pulse(waveform, spec);
      element.source.waveform = std::move(waveform);
    }
    if (valid) add(std::move(element));
  }

  // PULSE(V1 V2 TD TR TF PW PER): a negative TR, TF, PW or PER would make ngspice's pulse flat
  // without a word.
  bool check_pulse(const Waveform& waveform, const ast::SourceSpec& spec) {
    static constexpr const char* names[] = {"rise time", "fall time", "width", "period"};
    for (std::size_t i = 3; i < std::min<std::size_t>(waveform.args.size(), 7); ++i) {
      if (waveform.args[i] < 0) {
        diagnostics_.error(spec.args[i]->where, fmt::format("pulse {} must not be negative", names[i - 3]));
        return false;
      }
    }
    return true;
  }

  bool check_pwl(const Waveform& waveform, const ast::SourceSpec& spec) {
    for (std::size_t i = 2; i < waveform.args.size(); i += 2) {
      if (waveform.args[i] < waveform.args[i - 2]) {
        diagnostics_.error(spec.args[i]->where, "pwl times must not decrease");
        return false;
      }
    }
    if (waveform.repeat_from) {
      bool is_time_point = false;
      for (std::size_t i = 0; i < waveform.args.size(); i += 2)
        is_time_point |= waveform.args[i] == *waveform.repeat_from;
      if (!is_time_point) {
        const auto& option = *std::find_if(spec.options.begin(), spec.options.end(),
                                           [](const ast::Assignment& a) { return a.name.text == "r"; });
        diagnostics_.error(option.value->where, "pwl r= must be one of the time points");
        return false;
      }
    }
    return true;
  }

  void elaborate_card(const ast::VoltageControlled& card, const ast::Card&, const Instance& instance) {
    ElementKind kind = card.name.text[0] == 'e' ? ElementKind::vcvs : ElementKind::vccs;
    FlatElement element = element_of(kind, card.name, instance);
    element.nodes = {instance.node(card.positive.text), instance.node(card.negative.text),
                     instance.node(card.control_positive.text),
                     instance.node(card.control_negative.text)};
    auto v = value(card.gain, *instance.scope);
    if (!v) return;
    element.value = *v;
    add(std::move(element));
  }

  void elaborate_card(const ast::CurrentControlled& card, const ast::Card&, const Instance& instance) {
    ElementKind kind = card.name.text[0] == 'f' ? ElementKind::cccs : ElementKind::ccvs;
    FlatElement element = element_of(kind, card.name, instance);
    element.nodes = {instance.node(card.positive.text), instance.node(card.negative.text)};
    element.controls = {instance.element(card.control.text)};
    control_uses_.push_back({element.controls[0], 'v', card.control.where});
    auto v = value(card.gain, *instance.scope);
    if (!v) return;
    element.value = *v;
    add(std::move(element));
  }

  static ExpressionPtr expression_at(decltype(Expression::node) node, SourceRange where) {
    return std::make_shared<const Expression>(Expression{std::move(node), where});
  }

  // POLY(n): a B source of the polynomial in the n controls (node pairs' voltages for E G, the
  // currents of V sources for F H), with SPICE's order of the terms (polynomial_of).
  void elaborate_card(const ast::Polynomial& card, const ast::Card&, const Instance& instance) {
    const char letter = card.name.text[0];
    const bool current_controlled = letter == 'f' || letter == 'h';
    auto dimension = value(card.dimension, *instance.scope);
    if (!dimension) return;
    if (!(*dimension >= 1 && *dimension <= 16 && *dimension == std::floor(*dimension))) {
      diagnostics_.error(card.dimension->where, "poly() takes a whole number of controls from 1 to 16");
      return;
    }
    const auto controls = static_cast<std::size_t>(*dimension);
    const std::size_t control_words = current_controlled ? controls : 2 * controls;
    if (card.arguments.size() <= control_words) {
      diagnostics_.error(card.name.where, "poly(" + std::to_string(controls) + ") needs " + std::to_string(control_words) +
                                              (current_controlled ? (controls == 1 ? " voltage source" : " voltage sources")
                                                                  : " control nodes") +
                                              " and at least one coefficient");
      return;
    }
    std::vector<ExpressionPtr> variables;
    for (std::size_t k = 0; k < controls; ++k) {
      if (current_controlled) {
        const ast::Word& source = card.arguments[k];
        variables.push_back(expression_at(BranchCurrent{source.text}, source.where));
      } else {
        const ast::Word& positive = card.arguments[2 * k];
        const ast::Word& negative = card.arguments[2 * k + 1];
        variables.push_back(expression_at(NodeVoltage{positive.text, negative.text}, positive.where));
      }
    }
    std::vector<double> coefficients;
    for (std::size_t k = control_words; k < card.arguments.size(); ++k) {
      auto coefficient = parse_number(card.arguments[k].text);
      if (!coefficient) {
        diagnostics_.error(card.arguments[k].where, "expected a poly coefficient, not '" + card.arguments[k].text + "'");
        return;
      }
      coefficients.push_back(*coefficient);
    }
    FlatElement element = element_of(ElementKind::behavioral, card.name, instance);
    element.nodes = {instance.node(card.positive.text), instance.node(card.negative.text)};
    element.behavioral_is_voltage = letter == 'e' || letter == 'h';
    element.expression = substitute(polynomial_of(variables, coefficients, card.name.where), instance);
    if (element.expression) add(std::move(element));
  }

  // p0 + p1 x1 + ... + pn xn + p x1^2 + p x1 x2 + ... + p x1 xn + p x2^2 + ...: the terms of each
  // degree in lexicographic order of their non-decreasing variable indices (SPICE2's order);
  // zero coefficients are left out.
  static ExpressionPtr polynomial_of(const std::vector<ExpressionPtr>& variables,
                                     const std::vector<double>& coefficients, SourceRange where) {
    auto make = [&](decltype(Expression::node) node) { return expression_at(std::move(node), where); };
    ExpressionPtr sum;
    std::size_t next = 0;
    const std::size_t n = variables.size();
    for (std::size_t degree = 0; next < coefficients.size(); ++degree) {
      std::vector<std::size_t> indices(degree, 0);
      for (bool more = true; more && next < coefficients.size(); ++next) {
        if (coefficients[next] != 0) {
          ExpressionPtr term = make(Number{coefficients[next]});
          for (std::size_t index : indices) term = make(Binary{BinaryOperator::multiply, term, variables[index]});
          sum = sum ? make(Binary{BinaryOperator::add, sum, term}) : term;
        }
        // The next non-decreasing tuple: the rightmost index below n - 1 goes up, and those
        // after it take its new value.
        auto position = std::find_if(indices.rbegin(), indices.rend(), [&](std::size_t i) { return i + 1 < n; });
        more = position != indices.rend();
        if (more) {
          const std::size_t raised = ++*position;
          std::fill(indices.rbegin(), position, raised);
        }
      }
    }
    return sum ? sum : make(Number{0});
  }

  void elaborate_card(const ast::Behavioral& card, const ast::Card&, const Instance& instance) {
    FlatElement element = element_of(ElementKind::behavioral, card.name, instance);
    element.nodes = {instance.node(card.positive.text), instance.node(card.negative.text)};
    element.behavioral_is_voltage = card.quantity.text == "v";
    element.expression = substitute(card.expression, instance);
    if (element.expression) add(std::move(element));
  }

  // The flat name of a model of one of the wanted types, or nullopt (error reported).
  std::optional<std::string> model_for(const ast::Word& name, std::initializer_list<const char*> types,
                                       const char* element_kind, const Instance& instance) {
    auto [model, flat_name] = instance.definitions->find_model(name.text);
    if (!model) {
      diagnostics_.error(name.where, "model '" + name.text + "' is not defined");
      return std::nullopt;
    }
    if (!is_one_of(model->type.text, types)) {
      diagnostics_.error(name.where, fmt::format("model '{}' is a {} model; {} needs a {} model", name.text,
                                                 model->type.text, element_kind, fmt::join(types, " or ")));
      return std::nullopt;
    }
    return flat_name;
  }

  void elaborate_card(const ast::Diode& card, const ast::Card&, const Instance& instance) {
    FlatElement element = element_of(ElementKind::diode, card.name, instance);
    element.nodes = {instance.node(card.anode.text), instance.node(card.cathode.text)};
    auto model = model_for(card.model, {"d"}, "a diode", instance);
    element.value = 1.0;
    if (card.area) {
      auto area = value(*card.area, *instance.scope);
      if (!area) return;
      element.value = *area;
    }
    // ngspice 39 writes the area as area=..., older SPICEs after the model name.
    std::vector<ast::Assignment> parameters;
    for (const ast::Assignment& parameter : card.parameters) {
      if (parameter.name.text != "area") {
        parameters.push_back(parameter);
      } else if (card.area) {
        diagnostics_.error(parameter.name.where, "diode " + element.name + ": the area is given twice");
        return;
      } else if (auto area = value(parameter.value, *instance.scope)) {
        element.value = *area;
      } else {
        return;
      }
    }
    element.off = card.off;
    element_parameters(parameters, element, "diode", instance);
    if (!model) return;
    element.model = *model;
    add(std::move(element));
  }

  void elaborate_card(const ast::Mosfet& card, const ast::Card&, const Instance& instance) {
    FlatElement element = element_of(ElementKind::mosfet, card.name, instance);
    element.nodes = {instance.node(card.drain.text), instance.node(card.gate.text), instance.node(card.source.text),
                     instance.node(card.bulk.text)};
    bool valid = true;
    for (const ast::Assignment& parameter : card.parameters) {
      if (!is_one_of(parameter.name.text, {"l", "w", "ad", "as", "pd", "ps", "nrd", "nrs", "m"})) {
        diagnostics_.error(parameter.name.where,
                           "unknown parameter '" + parameter.name.text + "' for MOSFET " + element.name);
        valid = false;
      } else if (auto v = value(parameter.value, *instance.scope)) {
        element.instance_parameters[parameter.name.text] = *v;
      } else {
        valid = false;
      }
    }
    element.off = card.off;
    auto model = model_for(card.model, {"nmos", "pmos"}, "a MOSFET", instance);
    if (!model || !valid) return;
    element.model = *model;
    add(std::move(element));
  }

  void elaborate_card(const ast::VoltageSwitch& card, const ast::Card&, const Instance& instance) {
    FlatElement element = element_of(ElementKind::voltage_switch, card.name, instance);
    element.nodes = {instance.node(card.positive.text), instance.node(card.negative.text),
                     instance.node(card.control_positive.text),
                     instance.node(card.control_negative.text)};
    auto model = model_for(card.model, {"sw"}, "a voltage-controlled switch", instance);
    if (!model) return;
    element.model = *model;
    if (card.state) element.initially_on = card.state->text == "on";
    add(std::move(element));
  }

  void elaborate_card(const ast::CurrentSwitch& card, const ast::Card&, const Instance& instance) {
    FlatElement element = element_of(ElementKind::current_switch, card.name, instance);
    element.nodes = {instance.node(card.positive.text), instance.node(card.negative.text)};
    element.controls = {instance.element(card.control.text)};
    control_uses_.push_back({element.controls[0], 'v', card.control.where});
    auto model = model_for(card.model, {"csw"}, "a current-controlled switch", instance);
    if (!model) return;
    element.model = *model;
    if (card.state) element.initially_on = card.state->text == "on";
    add(std::move(element));
  }

  void elaborate_card(const ast::Instance& card, const ast::Card&, const Instance& instance) {
    const ast::Subcircuit* subcircuit = instance.definitions->find_subcircuit(card.subcircuit.text);
    if (!subcircuit) {
      diagnostics_.error(card.subcircuit.where,
                         "subcircuit '" + card.subcircuit.text + "' is not defined");
      return;
    }
    // Recursion, depth and size were checked (Hierarchy) before anything was built.
    if (card.nodes.size() != subcircuit->ports.size()) {
      diagnostics_.error(card.name.where, card.name.text + " connects " +
                                              count(card.nodes.size(), "node") + "; subcircuit '" +
                                              subcircuit->name.text + "' has " +
                                              count(subcircuit->ports.size(), "port"));
      return;
    }
    Instance inner;
    inner.prefix = instance.element(card.name.text) + ".";
    inner.global_nodes = instance.global_nodes;
    for (std::size_t i = 0; i < card.nodes.size(); ++i)
      inner.ports[subcircuit->ports[i].text] = instance.node(card.nodes[i].text);

    // Instance values are evaluated where the instance is; defaults inside the subcircuit.
    Scope scope{instance.scope, {}};
    std::set<std::string> overridden;
    for (const ast::Assignment& parameter : card.parameters) {
      bool declared = std::any_of(subcircuit->parameters.begin(), subcircuit->parameters.end(),
                                  [&](const ast::Assignment& p) { return p.name.text == parameter.name.text; });
      if (!declared) {
        diagnostics_.error(parameter.name.where, "subcircuit '" + subcircuit->name.text +
                                                     "' has no parameter '" + parameter.name.text + "'");
        return;
      }
      auto v = value(parameter.value, *instance.scope);
      if (!v) return;  // reported; expanding with the default would only add follow-up errors
      scope.values[parameter.name.text] = *v;
      overridden.insert(parameter.name.text);
    }
    std::vector<const ast::Card*> cards;
    std::vector<ast::Card> defaults;  // the defaults not overridden, as .param cards first
    ast::ParamCard default_parameters;
    for (const ast::Assignment& parameter : subcircuit->parameters)
      if (!overridden.count(parameter.name.text)) default_parameters.assignments.push_back(parameter);
    defaults.push_back(ast::Card{std::move(default_parameters), subcircuit->name.where});
    cards.push_back(&defaults.back());
    flatten_includes(subcircuit->body, cards);

    Definitions definitions{instance.definitions, inner.prefix, {}, {}};
    inner.scope = &scope;
    inner.definitions = &definitions;
    elaborate_body(cards, inner, scope, definitions);
  }

  // Collected by elaborate_body before the elements.
  void elaborate_card(const ast::ParamCard&, const ast::Card&, const Instance&) {}
  void elaborate_card(const ast::ModelCard&, const ast::Card&, const Instance&) {}
  void elaborate_card(const ast::Subcircuit&, const ast::Card&, const Instance&) {}
  void elaborate_card(const ast::Include&, const ast::Card&, const Instance&) {}

  bool at_top_level(const ast::Card& card, const Instance& instance, const char* what) {
    if (instance.prefix.empty()) return true;
    diagnostics_.warning(card.where, std::string(what) + " inside a subcircuit is ignored");
    return false;
  }

  void elaborate_card(const ast::TranCard& card, const ast::Card& whole, const Instance& instance) {
    if (!at_top_level(whole, instance, ".tran")) return;
    auto step = value(card.step, *instance.scope);
    auto stop = value(card.stop, *instance.scope);
    std::optional<double> start = 0.0;
    if (card.start) start = value(*card.start, *instance.scope);
    std::optional<double> max_step;
    if (card.max_step && !(max_step = value(*card.max_step, *instance.scope))) return;
    if (!step || !stop || !start) return;
    if (!(*step > 0)) {
      diagnostics_.error(card.step->where, ".tran needs a positive time step");
      return;
    }
    if (!(*stop > *start)) {
      diagnostics_.error(card.stop->where, ".tran needs a stop time after the start time");
      return;
    }
    if (max_step && *max_step < 0) {  // 0: the default, as in ngspice
      diagnostics_.error((*card.max_step)->where, ".tran needs a positive maximum step");
      return;
    }
    if (circuit_.tran)
      diagnostics_.warning(card.directive.where, "a second .tran replaces the first");
    circuit_.tran = Transient{*step, *stop, *start, max_step, card.uic, card.directive.where};
  }

  void elaborate_card(const ast::NodeValuesCard& card, const ast::Card&, const Instance& instance) {
    const bool ic = card.directive.text == "ic";
    auto& target = ic ? circuit_.initial_conditions : circuit_.nodesets;
    for (const ast::NodeAssignment& assignment : card.values) {
      auto v = value(assignment.value, *instance.scope);
      if (!v) continue;
      NodeValue given{instance.node(assignment.node.text),
                      assignment.reference ? instance.node(assignment.reference->text) : "", *v, assignment.node.where};
      if (ic && given.reference.empty() && !initial_condition_nodes_.insert(given.node).second)
        diagnostics_.warning(assignment.node.where,
                             ".ic of node '" + given.node + "' is given again; this value replaces the earlier one");
      target.push_back(std::move(given));
    }
  }

  void elaborate_card(const ast::OptionsCard& card, const ast::Card& whole, const Instance& instance) {
    if (!at_top_level(whole, instance, ".options")) return;
    for (const ast::OptionItem& item : card.items) {
      Option option{item.name.text, std::nullopt, item.word ? item.word->text : "", item.name.where};
      if (item.number && !(option.number = value(*item.number, *instance.scope))) continue;
      circuit_.options.push_back(std::move(option));
    }
  }

  void elaborate_card(const ast::OutputCard& card, const ast::Card& whole, const Instance& instance) {
    std::string what = "." + card.directive.text;
    if (!at_top_level(whole, instance, what.c_str())) return;
    bool first = true;
    for (const ast::OutputItem& item : card.items) {
      bool is_first = std::exchange(first, false);
      const std::string& function = item.function.text;
      SourceRange where = item.function.text.empty() ? item.args[0].where : item.function.where;
      if (function.empty()) {
        const std::string& word = item.args[0].text;
        if (is_first && card.directive.text != "save" && is_one_of(word, {"tran", "ac", "dc", "op"}))
          continue;  // .print tran v(1): the analysis
        if (word == "all") {
          circuit_.saves.push_back({OutputRequest::Kind::all, "", "", "", where});
          continue;
        }
        circuit_.saves.push_back({OutputRequest::Kind::node_voltage, instance.node(word), "", "", where});
      } else if (function == "v" && item.args.size() <= 2) {
        circuit_.saves.push_back({OutputRequest::Kind::node_voltage, instance.node(item.args[0].text),
                                  item.args.size() == 2 ? instance.node(item.args[1].text) : "", "",
                                  where});
      } else if (function == "i" && item.args.size() == 1) {
        circuit_.saves.push_back({OutputRequest::Kind::branch_current, "", "",
                                  instance.element(item.args[0].text), where});
      } else {
        diagnostics_.warning(where, "output '" + function + "(...)' is not supported and ignored");
      }
    }
  }

  void elaborate_card(const ast::GlobalCard&, const ast::Card& whole, const Instance& instance) {
    at_top_level(whole, instance, ".global");  // gathered in run()
  }

  void elaborate_card(const ast::TempCard& card, const ast::Card& whole, const Instance& instance) {
    if (!at_top_level(whole, instance, ".temp")) return;
    circuit_.temperature = value(card.value, *instance.scope);
    circuit_.temperature_where = card.value->where;
  }

  void elaborate_card(const ast::TitleCard& card, const ast::Card&, const Instance&) {
    circuit_.title = card.text;
  }

  void elaborate_card(const ast::IgnoredCard& card, const ast::Card&, const Instance&) {
    const std::string& directive = card.directive.text;
    if (is_one_of(directive, {"ac", "dc", "op", "noise", "tf", "pz", "sens", "disto", "sp", "pss"})) {
      if (has_tran_)
        diagnostics_.warning(card.directive.where,
                             "." + directive + " is ignored: padsim runs the transient analysis only");
      else
        diagnostics_.error(card.directive.where, "." + directive +
                                                     " is not supported: padsim runs transient "
                                                     "analysis (.tran) only");
    } else if (is_one_of(directive, {"width", "plot", "four", "fourier", "meas", "measure", "csparam"})) {
      diagnostics_.warning(card.directive.where, "." + directive + " is ignored");
    } else {
      diagnostics_.warning(card.directive.where, "unknown dot card '." + directive + "' is ignored");
    }
  }

  // ---- references -------------------------------------------------------------------------

  struct ControlUse {
    std::string element;
    char kind;  // the element letter it must be: 'v' or 'l'
    SourceRange where;
  };

  void check_references() {
    auto check = [&](const std::string& name, char kind, const SourceRange& where) {
      const char* what = kind == 'v' ? "voltage source" : "inductor";
      auto found = element_index_.find(name);
      if (found == element_index_.end())
        diagnostics_.error(where, std::string(what) + " '" + name + "' is not defined");
      else if (static_cast<char>(circuit_.elements[found->second].kind) != kind)
        diagnostics_.error(where, "'" + name + "' is not a " + what);
    };
    for (const ControlUse& use : control_uses_) check(use.element, use.kind, use.where);
    for (const auto& [name, where] : branch_current_uses_) check(name, 'v', where);
  }

  Diagnostics& diagnostics_;
  FlatCircuit circuit_;
  std::set<std::string> global_nodes_;
  std::size_t max_cards_;
  bool has_tran_ = false;
  std::unordered_map<std::string, std::size_t> element_index_;
  std::vector<ControlUse> control_uses_;
  std::vector<std::pair<std::string, SourceRange>> branch_current_uses_;
  std::unordered_set<std::string> initial_condition_nodes_;  // with a .ic v(node) so far
};

}  // namespace

std::optional<FlatCircuit> elaborate(const ast::Netlist& netlist, Diagnostics& diagnostics,
                                     std::size_t max_cards) {
  return Elaborator(diagnostics, max_cards).run(netlist);
}

std::optional<FlatCircuit> load(const std::filesystem::path& path, Diagnostics& diagnostics) {
  ast::Netlist netlist = parse_file(path, diagnostics);
  if (diagnostics.has_errors()) return std::nullopt;
  return elaborate(netlist, diagnostics);
}

}  // namespace netlist
