// Expression AST shared by the parser (which builds it) and src/mna (which compiles B sources
// into smooth functions plus predicates). Conditions stay visible: comparisons, logical
// operators, the ternary, if(), u() and the kinks of abs/min/max/limit are nodes here, so that
// src/mna can turn each of them into a predicate with a guard function.
#pragma once

#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "netlist/position.hpp"

namespace netlist {

struct Expression;
using ExpressionPtr = std::shared_ptr<const Expression>;

enum class UnaryOperator { negate, logical_not };
enum class BinaryOperator {
  add, subtract, multiply, divide, power,          // power: ^ and **
  less, less_equal, greater, greater_equal, equal, not_equal,
  logical_and, logical_or,
};

struct Number { double value; };
struct ParameterRef { std::string name; };            // resolved away by elaboration
struct NodeVoltage { std::string node, reference; };  // v(n) (reference empty) or v(n1, n2)
struct BranchCurrent { std::string element; };        // i(vname): current through a V source
struct Time {};                                        // `time`
struct Unary { UnaryOperator op; ExpressionPtr operand; };
struct Binary { BinaryOperator op; ExpressionPtr left, right; };
struct Conditional { ExpressionPtr condition, if_true, if_false; };  // c ? a : b, if(c, a, b)
// A function call: exp ln log log10 sqrt sin cos tan atan atan2 sinh cosh tanh abs min max pow
// pwr sgn u uramp limit floor ceil. Names are lower case; arity is checked by the parser.
struct Call { std::string function; std::vector<ExpressionPtr> arguments; };

struct Expression {
  std::variant<Number, ParameterRef, NodeVoltage, BranchCurrent, Time, Unary, Binary,
               Conditional, Call>
      node;
  SourceRange where;
  int height = 1;  // of the tree below: the parser bounds it, since every walk of it recurses
};

}  // namespace netlist
