// Shared by the mna tests: expression builders and one-shot model evaluation.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "mna/model.hpp"
#include "netlist/expression.hpp"

namespace mna::test {

inline netlist::ExpressionPtr make(auto node) {
  return std::make_shared<const netlist::Expression>(netlist::Expression{node, {}});
}
inline netlist::ExpressionPtr number(double value) { return make(netlist::Number{value}); }
inline netlist::ExpressionPtr voltage(std::string node, std::string reference = "") {
  return make(netlist::NodeVoltage{std::move(node), std::move(reference)});
}
inline netlist::ExpressionPtr current(std::string element) { return make(netlist::BranchCurrent{std::move(element)}); }
inline netlist::ExpressionPtr time() { return make(netlist::Time{}); }
inline netlist::ExpressionPtr binary(netlist::BinaryOperator op, netlist::ExpressionPtr l, netlist::ExpressionPtr r) {
  return make(netlist::Binary{op, std::move(l), std::move(r)});
}
inline netlist::ExpressionPtr conditional(netlist::ExpressionPtr c, netlist::ExpressionPtr a, netlist::ExpressionPtr b) {
  return make(netlist::Conditional{std::move(c), std::move(a), std::move(b)});
}
inline netlist::ExpressionPtr call(std::string function, std::vector<netlist::ExpressionPtr> arguments) {
  return make(netlist::Call{std::move(function), std::move(arguments)});
}

// f, q and both Jacobians (dense) of a model at (t, x, p).
struct DenseLoad {
  Vector f, q;
  Eigen::MatrixXd df, dq;
};
inline DenseLoad evaluate(Model& model, double t, const Vector& x, const padae::Predicates& p) {
  const int n = model.size();
  padae::Load load;
  load.f = Vector::Zero(n), load.q = Vector::Zero(n);
  load.df_dx.assign(model.pattern().nonzeros(), 0.0);
  load.dq_dx.assign(model.pattern().nonzeros(), 0.0);
  load.jacobian_requested = true;
  model.load(t, x, p, load);
  DenseLoad dense{load.f, load.q, Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n)};
  const auto& starts = model.pattern().column_starts();
  const auto& rows = model.pattern().row_indices();
  for (int column = 0; column < n; ++column)
    for (int k = starts[column]; k < starts[column + 1]; ++k) {
      dense.df(rows[k], column) = load.df_dx[k];
      dense.dq(rows[k], column) = load.dq_dx[k];
    }
  return dense;
}

inline int unknown(const Model& model, const std::string& label) {
  for (int i = 0; i < model.size(); ++i)
    if (model.unknowns().label(i) == label) return i;
  return -1;
}

}  // namespace mna::test
