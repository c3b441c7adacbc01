#include "mna/start.hpp"

#include "padae/steady_state.hpp"

namespace mna {

Start find_start(Model& model, double t0, bool use_initial_conditions, const padae::Options& options) {
  Start start;
  start.x = use_initial_conditions ? model.initial_conditions() : model.operating_point_guess();
  start.p = model.initial_predicates(t0, start.x);
  if (use_initial_conditions) {
    start.ok = true;
    return start;
  }
  model.hold_initial_voltages(true);
  padae::SteadyState op = padae::steady_state(model, t0, start.x, start.p, options);
  model.hold_initial_voltages(false);
  start.ok = op.converged;
  start.x = std::move(op.x);
  start.p = std::move(op.p);
  start.message = op.message;
  start.worst_unknown = op.worst_unknown;
  return start;
}

}  // namespace mna
