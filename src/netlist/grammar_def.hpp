// The X3 grammar of one card (a logical line). Included by parser.cpp only: X3 compiles slowly,
// so the grammar is instantiated in that one translation unit.
//
// Precedence in expressions, loosest first (as ngspice's B sources and .param):
//   c ? a : b,  ||,  &&,  == !=,  < <= > >=,  + -,  * /,  unary - + !,  ^ ** (left assoc.)
// so -2^2 is -(2^2) = -4, as ngspice computes it.
#pragma once

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>

#include <boost/fusion/include/at_c.hpp>
#include <boost/spirit/home/x3.hpp>

#include "netlist/ast.hpp"
#include "netlist/ast_adapted.hpp"
#include "netlist/error_handler.hpp"
#include "netlist/expression.hpp"

namespace netlist::parser {

using boost::fusion::at_c;
using x3::_attr;
using x3::_val;
using x3::_where;
using x3::lexeme;
using x3::lit;
using x3::no_case;

inline std::string lower(std::string_view text) {
  std::string result(text);
  for (char& c : result) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return result;
}

// The syntax of an unsigned decimal (digits with an optional fraction, an optional exponent),
// not its value: number_value converts it, so that one beyond double's range (1e400) is said to
// be out of range, as one below it is (x3::double_ failed on it: "expected a value"). An "e"
// without digits is left to the suffix (units), as in SPICE.
inline auto const unsigned_decimal =
    x3::lexeme[((+x3::digit >> -('.' >> *x3::digit)) | ('.' >> +x3::digit)) >>
               -(x3::no_case['e'] >> -x3::char_("+-") >> +x3::digit)];

// The power of ten of an engineering suffix; the letters after it are units and ignored
// ("10uF", "1kOhm"). Letters that are no suffix are units only ("5V"), as in SPICE. nullopt
// for mil, which is no power of ten.
inline std::optional<int> suffix_exponent(std::string_view letters) {
  std::string suffix = lower(letters.substr(0, 3));
  if (suffix == "meg") return 6;
  if (suffix == "mil") return std::nullopt;
  if (suffix.empty()) return 0;
  switch (suffix[0]) {
    case 'f': return -15;
    case 'p': return -12;
    case 'n': return -9;
    case 'u': return -6;
    case 'm': return -3;
    case 'k': return 3;
    case 'g': return 9;
    case 't': return 12;
    default: return 0;
  }
}

// The value of the whole text [first, last) of a number token (optional sign, mantissa,
// suffix, units); nullopt when it is not one or not finite. unsigned_decimal checks the syntax
// (nan and inf are none); the value is converted by std::from_chars with the suffix folded into the
// exponent, so that it is the double nearest to the decimal value (0.1u is 1e-7 exactly as
// written, and printing then parsing a double gives it back).
inline std::optional<double> number_value(Iterator first, Iterator last) {
  bool negative = false;
  if (first != last && (*first == '-' || *first == '+')) negative = *first++ == '-';
  Iterator mantissa_end = first;
  if (!x3::parse(mantissa_end, last, unsigned_decimal)) return std::nullopt;
  if (!std::all_of(mantissa_end, last, [](char c) { return std::isalpha(static_cast<unsigned char>(c)); }))
    return std::nullopt;
  std::string mantissa(first, mantissa_end);
  long long exponent = 0;
  if (auto e = mantissa.find_first_of("eE"); e != std::string::npos) {
    std::string_view digits = std::string_view(mantissa).substr(e + 1);
    if (!digits.empty() && digits[0] == '+') digits.remove_prefix(1);
    auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), exponent);
    if (error != std::errc() || end != digits.data() + digits.size()) return std::nullopt;
    mantissa.resize(e);
  }
  std::optional<int> shift = suffix_exponent(std::string_view(&*mantissa_end, static_cast<std::size_t>(last - mantissa_end)));
  std::string scaled = mantissa + "e" + std::to_string(exponent + shift.value_or(0));
  double value = 0;
  auto [end, error] = std::from_chars(scaled.data(), scaled.data() + scaled.size(), value);
  if (error != std::errc() || end != scaled.data() + scaled.size()) return std::nullopt;
  if (!shift) value = value * 254 / 1e7;  // mil: 25.4e-6
  if (!std::isfinite(value)) return std::nullopt;
  return negative ? -value : value;
}

// The deepest expression tree the parser builds (Expression::height).
inline constexpr int max_expression_height = 1000;

inline ExpressionPtr make_expression(decltype(Expression::node) node, SourceRange where) {
  auto height_of = [](const ExpressionPtr& e) { return e->height; };
  const int below = std::visit(
      [&](const auto& n) {
        using N = std::decay_t<decltype(n)>;
        if constexpr (std::is_same_v<N, Unary>) return height_of(n.operand);
        else if constexpr (std::is_same_v<N, Binary>) return std::max(height_of(n.left), height_of(n.right));
        else if constexpr (std::is_same_v<N, Conditional>)
          return std::max({height_of(n.condition), height_of(n.if_true), height_of(n.if_false)});
        else if constexpr (std::is_same_v<N, Call>) {
          int deepest = 0;
          for (const ExpressionPtr& argument : n.arguments) deepest = std::max(deepest, height_of(argument));
          return deepest;
        } else
          return 0;
      },
      node);
  return std::make_shared<const Expression>(Expression{std::move(node), std::move(where), below + 1});
}

// The range from the start of `first` to the end of `last` when both are on one line.
inline SourceRange span(const SourceRange& first, const SourceRange& last) {
  SourceRange result = first;
  if (first.begin.file == last.begin.file && first.begin.line == last.begin.line)
    result.length = std::max(first.length, last.begin.column + last.length - first.begin.column);
  return result;
}

template <typename Context>
CardContext& card_of(Context const& context) {
  return x3::get<card_context_tag>(context).get();
}

// ---- semantic actions -------------------------------------------------------------------

inline auto const make_word = [](auto& context) {
  auto const& range = _attr(context);
  _val(context) = ast::Word{lower(std::string(range.begin(), range.end())),
                            card_of(context).range(range.begin(), range.end())};
};

// A name (node, element, model) is printable: a control byte (a NUL from a binary file) would
// reach the CSV header and every message that names it.
inline auto const make_name = [](auto& context) {
  auto const& range = _attr(context);
  const auto control = std::find_if(range.begin(), range.end(), [](unsigned char c) { return c < 0x20 || c == 0x7f; });
  if (control != range.end())
    throw CardError{card_of(context).range(control, control + 1),
                    "the name " + quote(std::string(range.begin(), range.end())) + " contains a control character"};
  make_word(context);
};

inline auto const make_path = [](auto& context) {  // file paths keep their case and lose quotes
  auto const& range = _attr(context);
  std::string text(range.begin(), range.end());
  if (text.size() >= 2 && (text.front() == '"' || text.front() == '\''))
    text = text.substr(1, text.size() - 2);
  _val(context) = ast::Word{std::move(text), card_of(context).range(range.begin(), range.end())};
};

inline auto const make_number = [](auto& context) {
  auto const& range = _attr(context);
  auto value = number_value(range.begin(), range.end());
  if (!value) throw CardError{card_of(context).range(range.begin(), range.end()), "number out of range"};
  _val(context) = make_expression(Number{*value}, card_of(context).range(range.begin(), range.end()));
};

inline auto const assign = [](auto& context) { _val(context) = _attr(context); };

template <BinaryOperator op>
struct make_binary_t {
  template <typename Context>
  void operator()(Context& context) const {
    ExpressionPtr left = _val(context);
    ExpressionPtr right = _attr(context);
    // A chain of operators (a + b + c ...) nests one level per operator; the compilers and
    // evaluators that walk it recurse, and 10,000 terms overflowed their stack.
    if (std::max(left->height, right->height) >= max_expression_height)
      throw CardError{right->where, "expression too deep: more than " + std::to_string(max_expression_height) +
                                        " operators in a chain (split it into parameters or sources)"};
    SourceRange where = span(left->where, right->where);
    _val(context) = make_expression(Binary{op, std::move(left), std::move(right)}, std::move(where));
  }
};
template <BinaryOperator op>
inline make_binary_t<op> const make_binary{};

// X3's _where is the input after the match; ranges come from raw[] of the first token and
// the end of the match.
template <UnaryOperator op>
struct make_unary_t {
  template <typename Context>
  void operator()(Context& context) const {
    auto const& operator_token = at_c<0>(_attr(context));
    ExpressionPtr operand = at_c<1>(_attr(context));
    SourceRange where = span(card_of(context).range(operator_token.begin(), operator_token.end()),
                             operand->where);
    _val(context) = make_expression(Unary{op, std::move(operand)}, std::move(where));
  }
};
template <UnaryOperator op>
inline make_unary_t<op> const make_unary{};

inline auto const make_conditional = [](auto& context) {
  ExpressionPtr condition = _val(context);
  ExpressionPtr if_true = at_c<0>(_attr(context));
  ExpressionPtr if_false = at_c<1>(_attr(context));
  SourceRange where = span(condition->where, if_false->where);
  _val(context) = make_expression(
      Conditional{std::move(condition), std::move(if_true), std::move(if_false)}, std::move(where));
};

inline auto const make_node_voltage = [](auto& context) {
  auto const& start = at_c<0>(_attr(context));
  ast::Word const& node = at_c<1>(_attr(context));
  auto const& reference = at_c<2>(_attr(context));
  _val(context) = make_expression(NodeVoltage{node.text, reference ? reference->text : ""},
                                  card_of(context).range(start.begin(), _where(context).begin()));
};

inline auto const make_branch_current = [](auto& context) {
  auto const& start = at_c<0>(_attr(context));
  _val(context) = make_expression(BranchCurrent{at_c<1>(_attr(context)).text},
                                  card_of(context).range(start.begin(), _where(context).begin()));
};

inline auto const make_time = [](auto& context) {
  auto const& range = _attr(context);
  _val(context) = make_expression(Time{}, card_of(context).range(range.begin(), range.end()));
};

inline auto const make_parameter_ref = [](auto& context) {
  ast::Word const& name = _attr(context);
  _val(context) = make_expression(ParameterRef{name.text}, name.where);
};

struct FunctionArity {
  std::string_view name;
  std::size_t arguments;
};
inline constexpr std::array<FunctionArity, 25> functions{{
    {"exp", 1}, {"ln", 1}, {"log", 1}, {"log10", 1}, {"sqrt", 1}, {"sin", 1}, {"cos", 1},
    {"tan", 1}, {"atan", 1}, {"atan2", 2}, {"sinh", 1}, {"cosh", 1}, {"tanh", 1}, {"abs", 1},
    {"min", 2}, {"max", 2}, {"pow", 2}, {"pwr", 2}, {"sgn", 1}, {"u", 1}, {"uramp", 1},
    {"limit", 3}, {"floor", 1}, {"ceil", 1}, {"if", 3},
}};

inline auto const make_call = [](auto& context) {
  ast::Word const& name = at_c<0>(_attr(context));
  std::vector<ExpressionPtr> arguments = at_c<1>(_attr(context));
  SourceRange range = span(name.where, card_of(context).range(_where(context).begin() - 1,
                                                               _where(context).begin()));
  auto function = std::find_if(functions.begin(), functions.end(),
                               [&](const FunctionArity& f) { return f.name == name.text; });
  if (function == functions.end())
    throw CardError{range, "unknown function " + quote(name.text)};
  if (arguments.size() != function->arguments)
    throw CardError{range,
                    "function '" + name.text + "' takes " + std::to_string(function->arguments) +
                        (function->arguments == 1 ? " argument, not " : " arguments, not ") +
                        std::to_string(arguments.size())};
  if (name.text == "if")
    _val(context) = make_expression(
        Conditional{std::move(arguments[0]), std::move(arguments[1]), std::move(arguments[2])},
        std::move(range));
  else
    _val(context) = make_expression(Call{name.text, std::move(arguments)}, std::move(range));
};

// Names that expressions read as something other than a parameter: padsim's `time` and `pi`, and
// what ngspice's B sources also read as built-ins. ngspice accepts a parameter of any of them and
// then reads it in some places and the built-in in others (.param pi=3 is 3 in an R value and
// 3.14159 in a B source; .param time=5 and .param temper=50 are read nowhere), so padsim refuses it.
struct ReservedName {
  std::string_view name, meaning;
};
inline constexpr std::array<ReservedName, 5> reserved_names{{
    {"time", "the simulation time"},
    {"pi", "the constant 3.14159..."},
    {"e", "the constant 2.71828... in ngspice's B sources"},
    {"temper", "the circuit temperature in ngspice"},
    {"hertz", "the frequency of ngspice's AC analysis"},
}};

inline auto const make_parameter = [](auto& context) {
  ast::Word const& name = at_c<0>(_attr(context));
  auto reserved = std::find_if(reserved_names.begin(), reserved_names.end(),
                               [&](const ReservedName& r) { return r.name == name.text; });
  if (reserved != reserved_names.end())
    throw CardError{name.where, "'" + name.text + "' is reserved (" + std::string(reserved->meaning) +
                                    ") and cannot name a parameter"};
  _val(context) = ast::Assignment{name, at_c<1>(_attr(context))};
};

// Source specs from a keyword and its values: dc value, ac magnitude [phase].
inline auto const make_dc_spec = [](auto& context) {
  ast::SourceSpec spec;
  spec.kind = at_c<0>(_attr(context));
  spec.args.push_back(at_c<1>(_attr(context)));
  _val(context) = std::move(spec);
};
inline auto const make_ac_spec = [](auto& context) {
  ast::SourceSpec spec;
  spec.kind = at_c<0>(_attr(context));
  spec.args.push_back(at_c<1>(_attr(context)));
  if (auto const& phase = at_c<2>(_attr(context))) spec.args.push_back(*phase);
  _val(context) = std::move(spec);
};

// A waveform in parentheses: its name=value options may stand inside them or after them
// (ngspice reads "pwl(0 0 1u 1 r=0)" and "pwl(0 0 1u 1) r=0" alike).
inline auto const make_waveform_spec = [](auto& context) {
  ast::SourceSpec spec;
  spec.kind = at_c<0>(_attr(context));
  spec.args = at_c<1>(_attr(context));
  spec.options = at_c<2>(_attr(context));
  for (auto const& option : at_c<3>(_attr(context))) spec.options.push_back(option);
  _val(context) = std::move(spec);
};

inline auto const make_bare_spec = [](auto& context) {
  ast::SourceSpec spec;
  spec.kind.where = _attr(context)->where;
  spec.args.push_back(_attr(context));
  _val(context) = std::move(spec);
};

inline auto const set_option_number = [](auto& context) { _val(context).number = _attr(context); };
inline auto const set_option_word = [](auto& context) { _val(context).word = _attr(context); };
inline auto const make_option = [](auto& context) {
  ast::OptionItem item = at_c<1>(_attr(context)).value_or(ast::OptionItem{});
  item.name = at_c<0>(_attr(context));
  _val(context) = std::move(item);
};

// ---- nesting limit --------------------------------------------------------------------------

inline constexpr int max_expression_nesting = 200;

// nested[p]: p, counted as one level of expression nesting.
template <typename Subject>
struct nested_directive : x3::unary_parser<Subject, nested_directive<Subject>> {
  using base_type = x3::unary_parser<Subject, nested_directive<Subject>>;
  static bool const handles_container = Subject::handles_container;
  explicit nested_directive(Subject const& subject) : base_type(subject) {}

  template <typename It, typename Context, typename RContext, typename Attribute>
  bool parse(It& first, It const& last, Context const& context, RContext& rcontext,
             Attribute& attribute) const {
    CardContext& card = card_of(context);
    if (card.nesting >= max_expression_nesting)
      throw CardError{card.token_range(first), "expression nested too deeply"};
    ++card.nesting;
    struct Leave {
      CardContext& card;
      ~Leave() { --card.nesting; }
    } leave{card};
    return this->subject.parse(first, last, context, rcontext, attribute);
  }
};

struct nested_gen {
  template <typename Subject>
  nested_directive<typename x3::extension::as_parser<Subject>::value_type> operator[](
      Subject const& subject) const {
    return nested_directive<typename x3::extension::as_parser<Subject>::value_type>{
        x3::as_parser(subject)};
  }
};
inline nested_gen const nested{};

// ---- rules --------------------------------------------------------------------------------
// A rule's name is what an error says was expected: "expected a node name".

// Each card rule reports its own expectation failures.
struct two_terminal_card_id : card_error_handler {};
struct coupling_card_id : card_error_handler {};
struct source_card_id : card_error_handler {};
struct voltage_controlled_card_id : card_error_handler {};
struct current_controlled_card_id : card_error_handler {};
struct polynomial_card_id : card_error_handler {};
struct expression_controlled_card_id : card_error_handler {};
struct behavioral_card_id : card_error_handler {};
struct diode_card_id : card_error_handler {};
struct mosfet_card_id : card_error_handler {};
struct voltage_switch_card_id : card_error_handler {};
struct current_switch_card_id : card_error_handler {};
struct instance_card_id : card_error_handler {};
struct param_card_id : card_error_handler {};
struct model_card_id : card_error_handler {};
struct subckt_card_id : card_error_handler {};
struct ends_card_id : card_error_handler {};
struct include_card_id : card_error_handler {};
struct tran_card_id : card_error_handler {};
struct node_values_card_id : card_error_handler {};
struct options_card_id : card_error_handler {};
struct output_card_id : card_error_handler {};
struct temp_card_id : card_error_handler {};
struct global_card_id : card_error_handler {};

// Node and element names: anything up to a blank or one of = ( ) , { } ' ".
auto const name_char = ~x3::char_(" \t\r\n=(),{}'\"");
auto const identifier_char = x3::alnum | x3::char_('_');
auto const keyword = [](char const* text) { return lexeme[no_case[lit(text)] >> !identifier_char]; };

x3::rule<class node_id, ast::Word> const node = "a node name";
x3::rule<class element_name_id, ast::Word> const element_name = "an element name";
x3::rule<class model_name_id, ast::Word> const model_name = "a model name";
x3::rule<class source_name_id, ast::Word> const source_name = "a voltage source name";
x3::rule<class inductor_name_id, ast::Word> const inductor_name = "an inductor name";
x3::rule<class subcircuit_name_id, ast::Word> const subcircuit_name = "a subcircuit name";
x3::rule<class identifier_id, ast::Word> const identifier = "a name";
x3::rule<class directive_id, ast::Word> const directive = "a dot card";
x3::rule<class path_id, ast::Word> const path = "a file path";
x3::rule<class number_id, ExpressionPtr> const number = "a number";
x3::rule<class unsigned_number_id, ExpressionPtr> const unsigned_number = "a number";
x3::rule<class value_id, ExpressionPtr> const value = "a value";
x3::rule<class end_id> const end_of_card = "end of card";

// A lone '$' starts an inline comment (lines.cpp), so it is no name: printed back, it would be one.
auto const name_def = x3::raw[lexeme[!(lit('$') >> !name_char) >> +name_char]][make_name];
auto const node_def = name_def;
auto const element_name_def = name_def;
auto const model_name_def = name_def;
auto const source_name_def = name_def;
auto const inductor_name_def = name_def;
auto const subcircuit_name_def = name_def;
auto const identifier_def =
    x3::raw[lexeme[(x3::alpha | x3::char_('_')) >> *identifier_char]][make_word];
auto const directive_def = lit('.') >> x3::raw[lexeme[+x3::alnum]][make_word];
auto const path_def = x3::raw[lexeme[('"' >> *~x3::char_('"') >> '"') |
                                     ('\'' >> *~x3::char_('\'') >> '\'') |
                                     +~x3::char_(" \t")]][make_path];
auto const number_tail = *x3::alpha >> !(identifier_char | '.');
auto const number_def = x3::raw[lexeme[-x3::char_("+-") >> unsigned_decimal >> number_tail]][make_number];
auto const unsigned_number_def = x3::raw[lexeme[unsigned_decimal >> number_tail]][make_number];
auto const end_of_card_def = x3::eoi;

// Expressions.
x3::rule<class expression_id, ExpressionPtr> const expression = "an expression";
x3::rule<class logical_or_id, ExpressionPtr> const logical_or = "an expression";
x3::rule<class logical_and_id, ExpressionPtr> const logical_and = "an expression";
x3::rule<class equality_id, ExpressionPtr> const equality = "an expression";
x3::rule<class relational_id, ExpressionPtr> const relational = "an expression";
x3::rule<class additive_id, ExpressionPtr> const additive = "an expression";
x3::rule<class multiplicative_id, ExpressionPtr> const multiplicative = "an expression";
x3::rule<class unary_id, ExpressionPtr> const unary = "an expression";
x3::rule<class power_id, ExpressionPtr> const power = "an expression";
x3::rule<class exponent_id, ExpressionPtr> const exponent = "an expression";
x3::rule<class signed_operand_id, ExpressionPtr> const signed_operand = "an expression";
x3::rule<class primary_id, ExpressionPtr> const primary = "an expression";
x3::rule<class node_voltage_id, ExpressionPtr> const node_voltage = "v(node)";
x3::rule<class branch_current_id, ExpressionPtr> const branch_current = "i(vsource)";
x3::rule<class call_id, ExpressionPtr> const call = "a function call";
x3::rule<class arguments_id, std::vector<ExpressionPtr>> const arguments = "arguments";
x3::rule<class closing_paren_id> const closing_paren = "')'";
// Tokens whose position starts an expression node (a sequence with actions cannot raw[] them).
using TokenRange = boost::iterator_range<Iterator>;
x3::rule<class minus_token_id, TokenRange> const minus_token = "'-'";
x3::rule<class not_token_id, TokenRange> const not_token = "'!'";
x3::rule<class voltage_open_id, TokenRange> const voltage_open = "v(";
x3::rule<class current_open_id, TokenRange> const current_open = "i(";

auto const expression_def =
    nested[logical_or[assign] >> -(('?' > expression > ':' > expression)[make_conditional])];
auto const logical_or_def =
    logical_and[assign] >> *((lit("||") > logical_and)[make_binary<BinaryOperator::logical_or>]);
auto const logical_and_def =
    equality[assign] >> *((lit("&&") > equality)[make_binary<BinaryOperator::logical_and>]);
auto const equality_def =
    relational[assign] >> *((lit("==") > relational)[make_binary<BinaryOperator::equal>] |
                            (lit("!=") > relational)[make_binary<BinaryOperator::not_equal>]);
auto const relational_def =
    additive[assign] >> *((lit("<=") > additive)[make_binary<BinaryOperator::less_equal>] |
                          (lit(">=") > additive)[make_binary<BinaryOperator::greater_equal>] |
                          (lit('<') > additive)[make_binary<BinaryOperator::less>] |
                          (lit('>') > additive)[make_binary<BinaryOperator::greater>]);
auto const additive_def =
    multiplicative[assign] >> *((lit('+') > multiplicative)[make_binary<BinaryOperator::add>] |
                                (lit('-') > multiplicative)[make_binary<BinaryOperator::subtract>]);
auto const multiplicative_def =
    unary[assign] >> *(((lit('*') >> !lit('*')) > unary)[make_binary<BinaryOperator::multiply>] |
                       (lit('/') > unary)[make_binary<BinaryOperator::divide>]);
auto const minus_token_def = x3::raw[lit('-')];
auto const not_token_def = x3::raw[lit('!')];
auto const voltage_open_def = x3::raw[lexeme[no_case[lit('v')] >> '(']];
auto const current_open_def = x3::raw[lexeme[no_case[lit('i')] >> '(']];
auto const signed_operand_def = (minus_token > unary)[make_unary<UnaryOperator::negate>] |
                                (not_token > unary)[make_unary<UnaryOperator::logical_not>] |
                                (lit('+') > unary)[assign];
auto const unary_def = nested[signed_operand[assign] | power[assign]];
// Left-associative as in ngspice (2^3^2 is 64); a signed exponent takes a power chain of its own
// (2^-3^2 is 2^-9).
auto const power_def =
    primary[assign] >> *(((lit("**") | lit('^')) > exponent)[make_binary<BinaryOperator::power>]);
auto const exponent_def = nested[signed_operand[assign] | primary[assign]];
auto const primary_def = unsigned_number[assign] | (lit('(') > expression > closing_paren)[assign] |
                         (lit('{') > expression > '}')[assign] |
                         (lit('\'') > expression > '\'')[assign] | node_voltage[assign] |
                         branch_current[assign] | call[assign] |
                         x3::raw[keyword("time") >> !lit('(')][make_time] |
                         identifier[make_parameter_ref];
auto const closing_paren_def = lit(')');
auto const node_voltage_def =
    (voltage_open > node > -(',' > node) > closing_paren)
        [make_node_voltage];
auto const branch_current_def =
    (current_open > source_name > closing_paren)
        [make_branch_current];
auto const arguments_def = -(expression % ',');
auto const call_def = ((identifier >> '(') > arguments > closing_paren)[make_call];

// A value in a position: a number, {expression} or 'expression'.
auto const value_def = number[assign] | (lit('{') > expression > '}')[assign] |
                       (lit('\'') > expression > '\'')[assign];

x3::rule<class assignment_id, ast::Assignment> const assignment = "name=value";
x3::rule<class parameter_id, ast::Assignment> const parameter = "name=value";
x3::rule<class params_keyword_id> const params_keyword = "params:";
// Instance and model parameters take values; .param, subcircuit and instance parameters take
// expressions (braces optional).
auto const assignment_def = (identifier >> '=') > value;
auto const parameter_def = ((identifier >> '=') > expression)[make_parameter];
auto const params_keyword_def = lexeme[no_case[lit("params:")]];

// ---- element cards -------------------------------------------------------------------------

x3::rule<two_terminal_card_id, ast::TwoTerminal> const two_terminal_card = "an R, C or L card";
x3::rule<coupling_card_id, ast::Coupling> const coupling_card = "a K card";
x3::rule<source_card_id, ast::IndependentSource> const source_card = "a V or I card";
x3::rule<voltage_controlled_card_id, ast::VoltageControlled> const voltage_controlled_card = "an E or G card";
x3::rule<current_controlled_card_id, ast::CurrentControlled> const current_controlled_card = "an F or H card";
x3::rule<polynomial_card_id, ast::Polynomial> const polynomial_card = "an E, F, G or H card with POLY";
x3::rule<behavioral_card_id, ast::Behavioral> const behavioral_card = "a B card";
x3::rule<expression_controlled_card_id, ast::Behavioral> const expression_controlled_card =
    "an E or G card with an expression";
x3::rule<diode_card_id, ast::Diode> const diode_card = "a D card";
x3::rule<mosfet_card_id, ast::Mosfet> const mosfet_card = "an M card";
x3::rule<voltage_switch_card_id, ast::VoltageSwitch> const voltage_switch_card = "an S card";
x3::rule<current_switch_card_id, ast::CurrentSwitch> const current_switch_card = "a W card";
x3::rule<instance_card_id, ast::Instance> const instance_card = "an X card";

x3::rule<class source_spec_id, ast::SourceSpec> const source_spec = "a source value";
x3::rule<class waveform_spec_id, ast::SourceSpec> const waveform_spec = "a waveform";
x3::rule<class parenthesized_waveform_id, ast::SourceSpec> const parenthesized_waveform = "a waveform";
x3::rule<class bare_waveform_id, ast::SourceSpec> const bare_waveform = "a waveform";
x3::rule<class dc_spec_id, ast::SourceSpec> const dc_spec = "dc value";
x3::rule<class ac_spec_id, ast::SourceSpec> const ac_spec = "ac magnitude";
x3::rule<class bare_spec_id, ast::SourceSpec> const bare_spec = "a value";
x3::rule<class waveform_kind_id, ast::Word> const waveform_kind = "pulse, sin, exp, sffm or pwl";
x3::rule<class waveform_arguments_id, std::vector<ExpressionPtr>> const waveform_arguments = "a value";
x3::rule<class waveform_values_id, std::vector<ExpressionPtr>> const waveform_values = "a value";
x3::rule<class dc_word_id, ast::Word> const dc_word = "dc";
x3::rule<class ac_word_id, ast::Word> const ac_word = "ac";
x3::rule<class quantity_id, ast::Word> const quantity = "V= or I=";
x3::rule<class controlled_quantity_id, ast::Word> const controlled_quantity = "vol=, cur= or value=";
x3::rule<class polynomial_arguments_id, std::vector<ast::Word>> const polynomial_arguments =
    "a control or a coefficient";
x3::rule<class switch_state_id, ast::Word> const switch_state = "on or off";
x3::rule<class instance_node_id, ast::Word> const instance_node = "a node name";
x3::rule<class instance_nodes_id, std::vector<ast::Word>> const instance_nodes = "a node name";

auto const two_terminal_card_def =
    element_name > node > node > value > *assignment > end_of_card;
auto const coupling_card_def =
    element_name > inductor_name > inductor_name > value > end_of_card;
auto const waveform_kind_def =
    x3::raw[keyword("pulse") | keyword("sin") | keyword("exp") | keyword("sffm") | keyword("pwl")][make_word];
auto const dc_word_def = x3::raw[keyword("dc")][make_word];
auto const ac_word_def = x3::raw[keyword("ac")][make_word];
auto const waveform_spec_def = parenthesized_waveform | bare_waveform;
auto const parenthesized_waveform_def =
    ((waveform_kind >> '(') > waveform_arguments > *assignment > closing_paren > *assignment)[make_waveform_spec];
// SPICE also takes a waveform's values without parentheses: "PULSE 0 5 1u 1n 1n 2u 5u".
auto const bare_waveform_def = (waveform_kind >> !lit('(')) > waveform_values > *assignment;
auto const waveform_arguments_def = *(value >> -lit(','));
auto const waveform_values_def = +(value >> -lit(','));
auto const dc_spec_def = (dc_word > value)[make_dc_spec];
auto const ac_spec_def = (ac_word > value > -value)[make_ac_spec];
auto const bare_spec_def = value[make_bare_spec];
auto const source_spec_def = waveform_spec | dc_spec | ac_spec | bare_spec;
auto const source_card_def = element_name > node > node > *source_spec > end_of_card;
auto const voltage_controlled_card_def =
    element_name > node > node > node > node > value > end_of_card;
auto const current_controlled_card_def =
    element_name > node > node > source_name > value > end_of_card;
// A control pair may stand in parentheses, "(a, 0)", as ngspice takes it.
auto const polynomial_arguments_def =
    +(((lit('(') > node > -lit(',') > node > closing_paren) | node) >> -lit(','));
auto const polynomial_card_def = element_name > node > node > keyword("poly") > '(' > unsigned_number >
                                 closing_paren > polynomial_arguments > end_of_card;
auto const quantity_def = x3::raw[keyword("v") | keyword("i")][make_word];
auto const behavioral_card_def =
    element_name > node > node > quantity > '=' > expression > end_of_card;
// ngspice's E and G with an expression: "E1 out 0 vol='2*v(a)'", "G1 0 out cur={...}", "value=".
auto const controlled_quantity_def = x3::raw[keyword("vol") | keyword("cur") | keyword("value")][make_word];
auto const expression_controlled_card_def =
    element_name > node > node > controlled_quantity > '=' > expression > end_of_card;
auto const diode_card_def = element_name > node > node > model_name > -value >
                            x3::matches[keyword("off")] > *assignment > end_of_card;
auto const mosfet_card_def = element_name > node > node > node > node > model_name > *assignment >
                             x3::matches[keyword("off")] > end_of_card;
auto const switch_state_def = x3::raw[keyword("on") | keyword("off")][make_word];
auto const voltage_switch_card_def =
    element_name > node > node > node > node > model_name > -switch_state > end_of_card;
auto const current_switch_card_def =
    element_name > node > node > source_name > model_name > -switch_state > end_of_card;
auto const instance_node_def = !params_keyword >> node >> !lit('=');
auto const instance_nodes_def = +instance_node;
auto const instance_card_def =
    element_name > instance_nodes > -params_keyword > *parameter > end_of_card;

// ---- dot cards -----------------------------------------------------------------------------

x3::rule<param_card_id, std::vector<ast::Assignment>> const param_card = "a .param card";
x3::rule<model_card_id, ast::ModelCard> const model_card = "a .model card";
x3::rule<subckt_card_id, ast::Subcircuit> const subckt_card = "a .subckt card";
x3::rule<ends_card_id, std::optional<ast::Word>> const ends_card = "an .ends card";
x3::rule<include_card_id, ast::Include> const include_card = "an .include card";
x3::rule<tran_card_id, ast::TranCard> const tran_card = "a .tran card";
x3::rule<node_values_card_id, ast::NodeValuesCard> const node_values_card = "an .ic card";
x3::rule<options_card_id, ast::OptionsCard> const options_card = "an .options card";
x3::rule<output_card_id, ast::OutputCard> const output_card = "a .save card";
x3::rule<temp_card_id, ast::TempCard> const temp_card = "a .temp card";
x3::rule<global_card_id, ast::GlobalCard> const global_card = "a .global card";

x3::rule<class parameters_id, std::vector<ast::Assignment>> const parameters = "name=value";
x3::rule<class model_type_id, ast::Word> const model_type = "a model type";
x3::rule<class model_parameters_id, std::vector<ast::Assignment>> const model_parameters =
    "model parameters";
x3::rule<class port_id, ast::Word> const port = "a node name";
x3::rule<class node_assignment_id, ast::NodeAssignment> const node_assignment = "v(node)=value";
x3::rule<class node_assignments_id, std::vector<ast::NodeAssignment>> const node_assignments =
    "v(node)=value";
x3::rule<class option_item_id, ast::OptionItem> const option_item = "an option";
x3::rule<class option_value_id, ast::OptionItem> const option_value = "a value";
x3::rule<class output_item_id, ast::OutputItem> const output_item = "an output";
x3::rule<class output_call_id, ast::OutputItem> const output_call = "v(node) or i(vsource)";
x3::rule<class output_word_id, ast::OutputItem> const output_word = "a node name";
x3::rule<class node_list_id, std::vector<ast::Word>> const node_list = "a node name";
x3::rule<class output_function_id, ast::Word> const output_function = "v or i";
x3::rule<class section_id, ast::Word> const section = "a library section name";

auto const parameters_def = +parameter;
auto const param_card_def = lexeme[no_case[lit(".param")]] > parameters > end_of_card;
auto const model_type_def = identifier;
auto const model_parameters_def = ('(' > *(assignment >> -lit(',')) > closing_paren) | *assignment;
auto const model_card_def =
    lexeme[no_case[lit(".model")]] > model_name > model_type > model_parameters > end_of_card;
auto const port_def = !params_keyword >> node >> !lit('=');
auto const subckt_card_def = lexeme[no_case[lit(".subckt")]] > subcircuit_name > *port >
                             -params_keyword > *parameter > end_of_card;
auto const ends_card_def = lexeme[no_case[lit(".ends")]] > -subcircuit_name > end_of_card;
auto const section_def = name_def;
auto const include_card_def = directive > path > -section > end_of_card;
auto const tran_card_def = directive > value > value > -value > -value >
                           x3::matches[keyword("uic")] > end_of_card;
auto const node_assignment_def =
    lexeme[no_case[lit('v')] >> '('] > node > -(',' > node) > closing_paren > '=' > value;
auto const node_assignments_def = +node_assignment;
auto const node_values_card_def = directive > node_assignments > end_of_card;
auto const option_value_def = value[set_option_number] | node[set_option_word];
auto const option_item_def = (identifier >> -('=' > option_value))[make_option];
auto const options_card_def = directive > *option_item > end_of_card;
auto const output_function_def = x3::raw[lexeme[+x3::alpha >> &lit('(')]][make_word];
auto const node_list_def = node % ',';
auto const output_call_def = (output_function >> '(') > node_list > closing_paren;
auto const output_word_def = x3::attr(ast::Word{}) >> x3::repeat(1)[node];
auto const output_item_def = output_call | output_word;
auto const output_card_def = directive > *output_item > end_of_card;
auto const temp_card_def = directive > value > end_of_card;
auto const global_card_def = directive > +node > end_of_card;

// In several groups: the preprocessor takes at most 64 arguments per macro.
BOOST_SPIRIT_DEFINE(node, element_name, model_name, source_name, inductor_name, subcircuit_name,
                    identifier, directive, path, number, unsigned_number, value, end_of_card,
                    expression, logical_or, logical_and, equality, relational, additive,
                    multiplicative)
BOOST_SPIRIT_DEFINE(minus_token, not_token, voltage_open, current_open)
BOOST_SPIRIT_DEFINE(unary, signed_operand, power, exponent, primary, node_voltage, branch_current, call, arguments,
                    closing_paren, assignment, parameter, params_keyword, two_terminal_card,
                    coupling_card, source_card, voltage_controlled_card, current_controlled_card,
                    behavioral_card, diode_card, mosfet_card, voltage_switch_card, current_switch_card,
                    polynomial_card, polynomial_arguments, expression_controlled_card,
                    controlled_quantity)
BOOST_SPIRIT_DEFINE(instance_card, source_spec, waveform_spec, dc_spec, ac_spec, bare_spec,
                    waveform_kind, waveform_arguments, waveform_values, parenthesized_waveform,
                    bare_waveform, dc_word, ac_word, quantity, switch_state, instance_node, instance_nodes,
                    param_card, model_card, subckt_card, ends_card, include_card, tran_card,
                    node_values_card, options_card)
BOOST_SPIRIT_DEFINE(output_card, temp_card, global_card, parameters, model_type, model_parameters, port,
                    node_assignment, node_assignments, option_item, option_value, output_item,
                    output_call, output_word, node_list, output_function, section)

}  // namespace netlist::parser
