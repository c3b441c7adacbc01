// Drives an integrator to t_end, calling on_step(outcome) after every step.
#pragma once

#include "padae/integrator.hpp"

namespace padae::testing {

template <class OnStep>
bool run_until(Integrator& integrator, double t_end, OnStep on_step) {
  while (integrator.time() < t_end) {
    StepOutcome outcome = integrator.step(t_end);
    if (outcome.kind == StepKind::failed) return false;
    on_step(outcome);
  }
  return true;
}

inline bool run_until(Integrator& integrator, double t_end) {
  return run_until(integrator, t_end, [](const StepOutcome&) {});
}

}  // namespace padae::testing
