#include "mna/structure.hpp"

#include <algorithm>
#include <numeric>
#include <queue>

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

// The elements on a path from a to b through `edges` (a spanning forest), by breadth-first search.
std::vector<std::string> path_elements(const std::vector<Edge>& edges, int vertices, int a, int b) {
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
  std::vector<std::string> names;
  for (int v = b; v != a && via[v] >= 0;) {
    const Edge& e = edges[via[v]];
    names.push_back(e.element);
    v = e.a == v ? e.b : e.a;
  }
  return names;
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
      std::vector<std::string> loop = path_elements(forest, n + 1, e.a, e.b);
      loop.push_back(e.element);
      throw ModelError(context + "loop of voltage sources" + std::string(dc ? " and inductors" : "") + ": " +
                       join_names(loop) + " (the currents around it are undetermined)");
    }
    forest.push_back(e);
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
    if (!cut.empty()) message += "; only " + join_names(cut) + " connect them to the rest (a cut-set of " +
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

}  // namespace mna
