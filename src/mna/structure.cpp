#include "mna/structure.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <map>
#include <numeric>
#include <queue>
#include <sstream>

namespace mna {

namespace {

class DisjointSets {
 public:
  explicit DisjointSets(int n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int find(int i) { return parent_[i] == i ? i : parent_[i] = find(parent_[i]); }
  bool join(int a, int b) {
    a = find(a), b = find(b);
    if (a == b) return false;
    parent_[a] = b;
    return true;
  }

 private:
  std::vector<int> parent_;
};

std::string join_names(const std::vector<std::string>& names) {
  std::string text;
  for (const auto& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

// The edges on a path from a to b through `edges` (a spanning forest), by breadth-first search.
std::vector<Edge> path_edges(const std::vector<Edge>& edges, int vertices, int a, int b) {
  std::vector<std::vector<std::pair<int, int>>> adjacent(vertices);
  for (int k = 0; k < static_cast<int>(edges.size()); ++k) {
    adjacent[edges[k].a].emplace_back(edges[k].b, k);
    adjacent[edges[k].b].emplace_back(edges[k].a, k);
  }
  std::vector<int> via(vertices, -2);
  std::queue<int> frontier;
  via[a] = -1, frontier.push(a);
  while (!frontier.empty()) {
    const int v = frontier.front();
    frontier.pop();
    for (auto [w, k] : adjacent[v])
      if (via[w] == -2) via[w] = k, frontier.push(w);
  }
  std::vector<Edge> path;
  for (int v = b; v != a && via[v] >= 0;) {
    const Edge& e = edges[via[v]];
    path.push_back(e);
    v = e.a == v ? e.b : e.a;
  }
  return path;
}

// "loop of voltage sources", "... and inductors", "loop of inductors": what the loop holds.
std::string loop_kind(const std::vector<Edge>& loop) {
  const bool inductors = std::any_of(loop.begin(), loop.end(), [](const Edge& e) { return e.connection == Connection::inductive; });
  const bool sources = std::any_of(loop.begin(), loop.end(), [](const Edge& e) { return e.connection != Connection::inductive; });
  return !inductors ? "loop of voltage sources" : sources ? "loop of voltage sources and inductors" : "loop of inductors";
}

void check_edges(const Model& model, StartKind start, std::vector<Edge> edges, const std::string& context) {
  const Unknowns& unknowns = model.unknowns();
  const int n = unknowns.size();
  const int ground_vertex = n;  // vertices: unknown indices (only nodes used), plus ground
  for (Edge& e : edges) {
    if (e.a == ground) e.a = ground_vertex;
    if (e.b == ground) e.b = ground_vertex;
  }
  const bool dc = start == StartKind::operating_point;
  auto is_node = [&](int i) {
    return unknowns.category(i) == UnknownCategory::node_voltage || unknowns.category(i) == UnknownCategory::internal_node;
  };

  // Loops of voltage-defined branches (and inductors at DC).
  DisjointSets loops(n + 1);
  std::vector<Edge> forest;
  for (const Edge& e : edges) {
    const bool fixes_voltage = e.connection == Connection::voltage_defined || (dc && e.connection == Connection::inductive);
    if (!fixes_voltage) continue;
    if (!loops.join(e.a, e.b)) {
      std::vector<Edge> loop = path_edges(forest, n + 1, e.a, e.b);
      loop.push_back(e);
      std::vector<std::string> names;
      for (const Edge& l : loop) names.push_back(l.element);
      throw ModelError(context + loop_kind(loop) + ": " + join_names(names) + " (the currents around it are undetermined" +
                       (loop_kind(loop) != "loop of voltage sources" ? " at DC: inductors are shorts there" : "") + ")");
    }
    forest.push_back(e);
  }
  // The operating point holds the .ic node voltages, each like a source to ground: one on a node
  // those branches (or another .ic) fix already closes a loop with them.
  if (dc)
    for (const auto& [node, value] : model.circuit().initial_voltages) {
      const Edge held{model.find_node(node), ground_vertex, Connection::voltage_defined, ".ic v(" + node + ")"};
      if (held.a < 0) continue;
      if (!loops.join(held.a, held.b)) {
        const std::vector<Edge> fixing = path_edges(forest, n + 1, held.b, held.a);  // from the node on
        std::vector<std::string> names, branches;  // branches: the elements among them
        for (const Edge& f : fixing) {
          names.push_back(f.element);
          if (!f.element.starts_with(".ic ")) branches.push_back(f.element);
        }
        throw ModelError::at_initial_condition(
            context + held.element + " is on a node that " + join_names(names) + (names.size() == 1 ? " fixes" : " fix") +
                (loop_kind(fixing) != "loop of voltage sources" ? " (inductors are shorts at DC)" : "") +
                ": the operating point holds .ic voltages, which leaves the current" +
                (branches.size() == 1 ? " of " : "s of ") + join_names(branches) +
                " undetermined; drop this .ic, or start from initial conditions (uic)",
            node);
      }
      forest.push_back(held);
    }

  // Paths to ground.
  DisjointSets paths(n + 1);
  for (const Edge& e : edges) {
    const bool path = e.connection != Connection::current_defined && (!dc || e.connection != Connection::capacitive);
    if (path) paths.join(e.a, e.b);
  }
  std::vector<std::vector<int>> floating(n + 1);
  for (int i = 0; i < n; ++i)
    if (is_node(i) && paths.find(i) != paths.find(ground_vertex)) floating[paths.find(i)].push_back(i);
  for (int root = 0; root <= n; ++root) {
    if (floating[root].empty()) continue;
    std::vector<std::string> nodes, cut;
    for (int i : floating[root])
      nodes.push_back(unknowns.category(i) == UnknownCategory::node_voltage ? unknowns.owner(i) : unknowns.label(i));
    for (const Edge& e : edges) {
      const bool crosses = (paths.find(e.a) == root) != (paths.find(e.b) == root);
      if (crosses && std::find(cut.begin(), cut.end(), e.element) == cut.end()) cut.push_back(e.element);
    }
    std::string message = context + (dc ? "no DC path to ground from node(s) " : "no path to ground from node(s) ") + join_names(nodes);
    if (!cut.empty()) message += "; only " + join_names(cut) + (cut.size() == 1 ? " connects" : " connect") + " them to the rest (a cut-set of " +
                                 (dc ? "current sources and capacitors" : "current sources") + ")";
    if (dc) message += "; add a resistance to ground, or start from initial conditions (uic)";
    throw ModelError(message);
  }
}

}  // namespace

void check_structure(const Model& model, StartKind start) { check_edges(model, start, model.edges(), ""); }

void check_mode_structure(const Model& model, StartKind start, const padae::Predicates& mode) {
  check_edges(model, start, model.edges(mode), "with the initial switch and diode states: ");
}

std::string mode_structure_fault(const Model& model, const padae::Predicates& mode) {
  try {
    check_edges(model, StartKind::initial_conditions, model.edges(mode), "");
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

namespace {

// The model's f, q and their Jacobians on its pattern at (t, x, p); false outside its domain.
bool load_jacobians(Model& model, double t, const Vector& x, const padae::Predicates& p, padae::Load& load) {
  const int n = model.size();
  const auto nonzeros = static_cast<std::size_t>(model.pattern().nonzeros());
  load.f.setZero(n);
  load.q.setZero(n);
  load.df_dx.assign(nonzeros, 0.0);
  load.dq_dx.assign(nonzeros, 0.0);
  load.jacobian_requested = true;
  return model.load(t, x, p, load) == padae::EvalStatus::ok;
}

// The start's Newton matrix, dense: df/dx (operating point) or df/dx + c dq/dx (uic).
bool dense_matrix(Model& model, double t, const Vector& x, const padae::Predicates& p, double c, Eigen::MatrixXd& out) {
  padae::Load load;
  const int n = model.size();
  const padae::Pattern& pattern = model.pattern();
  if (!load_jacobians(model, t, x, p, load)) return false;
  out.setZero(n, n);
  for (int column = 0; column < n; ++column)
    for (int k = pattern.column_starts()[column]; k < pattern.column_starts()[column + 1]; ++k)
      out(pattern.row_indices()[k], column) += load.df_dx[k] + c * load.dq_dx[k];
  // Auxiliary modes (switch states, diode modes) are not solved for: identity rows, as the
  // integrator's Newton matrix has them.
  for (int i = 0; i < n; ++i)
    if (model.kind(i) == padae::UnknownKind::auxiliary) {
      out.row(i).setZero();
      out(i, i) = 1;
    }
  return out.allFinite();
}

}  // namespace

// Three K cards each within |k| <= 1 ran to 1e64 V (in ngspice too). The matrix is the devices'
// own, evaluated once; each group of branch currents joined by mutual terms is checked alone.
void check_inductance_matrices(Model& model) {
  const auto& elements = model.circuit().elements;
  auto is_coupling = [](const ElementSpec& e) { return std::tolower(e.type) == 'k'; };
  if (std::none_of(elements.begin(), elements.end(), is_coupling)) return;
  const int n = model.size();
  padae::Load load;
  if (!load_jacobians(model, 0, Vector::Zero(n), padae::Predicates(static_cast<std::size_t>(model.predicate_count()), 0), load))
    return;
  const padae::Pattern& pattern = model.pattern();
  auto is_branch = [&](int i) { return model.unknowns().category(i) == UnknownCategory::branch_current; };
  DisjointSets groups(n);
  for (int column = 0; column < n; ++column)
    for (int s = pattern.column_starts()[column]; s < pattern.column_starts()[column + 1]; ++s)
      if (const int row = pattern.row_indices()[s]; row != column && load.dq_dx[s] != 0 && is_branch(row) && is_branch(column))
        groups.join(row, column);
  std::map<int, std::vector<int>> windings;
  for (int i = 0; i < n; ++i)
    if (is_branch(i)) windings[groups.find(i)].push_back(i);
  for (const auto& [root, members] : windings) {
    if (members.size() < 2) continue;
    const auto size = static_cast<Eigen::Index>(members.size());
    Eigen::MatrixXd inductance(size, size);
    for (Eigen::Index r = 0; r < size; ++r)
      for (Eigen::Index c = 0; c < size; ++c) {
        const int s = pattern.find(members[r], members[c]);
        inductance(r, c) = s < 0 ? 0.0 : -load.dq_dx[s];
      }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(inductance, Eigen::EigenvaluesOnly);
    const double lowest = eigen.eigenvalues().minCoeff(), highest = eigen.eigenvalues().maxCoeff();
    if (lowest >= -1e-9 * highest) continue;
    std::vector<std::string> inductors, couplings;
    for (int member : members) inductors.push_back(model.unknowns().owner(member));
    for (const auto& spec : elements)
      if (is_coupling(spec) && !spec.controls.empty() &&
          std::find(inductors.begin(), inductors.end(), spec.controls[0]) != inductors.end())
        couplings.push_back(spec.name);
    std::ostringstream eigenvalue;
    eigenvalue << std::setprecision(3) << lowest;
    throw ModelError("the couplings " + join_names(couplings) + " make the inductance matrix of " + join_names(inductors) +
                         " indefinite (an eigenvalue of " + eigenvalue.str() +
                         " H): those windings would store negative energy, and their currents grow without bound",
                     couplings.empty() ? "" : couplings.front());
  }
}

std::string singular_linear_equations(Model& model, StartKind start, const padae::Predicates& mode, double t, double time_scale) {
  const int n = model.size();
  if (n == 0 || n > kSingularCheckMaxUnknowns) return "";
  const bool dc = start == StartKind::operating_point;
  model.hold_initial_voltages(dc);
  // Two points: where the start began, and away from it; linear equations have one matrix.
  const Vector x0 = dc ? model.operating_point_guess() : model.initial_conditions();
  Vector x1 = x0;
  for (int i = 0; i < n; ++i)
    if (model.kind(i) != padae::UnknownKind::auxiliary) x1[i] += 0.37 * ((i * 7919) % 13 - 6) + 0.11;
  const double c = dc ? 0.0 : 1.0 / time_scale;
  Eigen::MatrixXd a0, a1;
  const bool evaluated = dense_matrix(model, t, x0, mode, c, a0) && dense_matrix(model, t, x1, mode, c, a1);
  model.hold_initial_voltages(false);
  if (!evaluated) return "";
  const double largest = a0.cwiseAbs().maxCoeff();
  if (!(largest > 0) || (a1 - a0).cwiseAbs().maxCoeff() > 1e-12 * largest) return "";  // not linear
  // Equilibrate rows, then columns, so that a large conductance beside a small one is not
  // mistaken for a rank deficiency.
  Eigen::MatrixXd scaled = a0;
  for (int i = 0; i < n; ++i) {
    const double m = scaled.row(i).cwiseAbs().maxCoeff();
    if (m > 0) scaled.row(i) /= m;
  }
  for (int j = 0; j < n; ++j) {
    const double m = scaled.col(j).cwiseAbs().maxCoeff();
    if (m > 0) scaled.col(j) /= m;
  }
  Eigen::FullPivLU<Eigen::MatrixXd> lu(scaled);
  lu.setThreshold(1e-13 * n);
  if (lu.rank() == n) return "";
  const Eigen::VectorXd null = lu.kernel().col(0);
  const double top = null.cwiseAbs().maxCoeff();
  std::vector<std::string> names, elements;  // elements: those at the undetermined nodes
  std::vector<char> undetermined(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i)
    if (std::abs(null[i]) > 1e-6 * top) {
      names.push_back(model.unknowns().label(i));
      undetermined[i] = model.unknowns().category(i) == UnknownCategory::node_voltage;
    }
  auto at_undetermined = [&](int node) { return node >= 0 && undetermined[node]; };
  for (const Edge& e : model.edges())
    if ((at_undetermined(e.a) || at_undetermined(e.b)) && std::find(elements.begin(), elements.end(), e.element) == elements.end())
      elements.push_back(e.element);
  return std::string("the circuit equations are singular") + (dc ? " at the operating point" : " at the start") +
         " (linear, rank " + std::to_string(lu.rank()) + " of " + std::to_string(n) + "): they do not determine " +
         join_names(names) + (elements.empty() ? "" : ", where " + join_names(elements) + (elements.size() == 1 ? " connects" : " connect")) +
         " (a controlled source fixing its own control, sources that define each other, values that cancel, or a "
         "conductance lost to rounding beside the others, as ROFF = 1e20 beside 1 kOhm)";
}

}  // namespace mna
