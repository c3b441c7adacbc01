// The paper's central claim, measured (section 7 of shared/docs/predicate-dae.md): the masses
// example (4) integrated with each Heaviside step replaced by a smooth "logical function" of
// width eps (Ehle and Haug), against the predicate form. Same integrator, same tolerance;
// error against the closed form at the end, wall time per run, steps.
#include <benchmark/benchmark.h>

#include <cmath>

#include "padae/integrator.hpp"
#include "paper_masses.hpp"

namespace {

using padae::EvalStatus;
using padae::Predicates;
using padae::Vector;
using padae::testing::Masses;
using padae::testing::MassesClosedForm;

// (4) with the steps smoothed: L(s) = (1 + tanh(s / eps)) / 2.
class MassesLogicalFunction : public padae::SemiExplicitSystem {
 public:
  MassesLogicalFunction(Masses m, double width)
      : SemiExplicitSystem({padae::testing::kDifferential, padae::testing::kDifferential}),
        m_(m),
        width_(width) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    auto step = [&](double s) { return 0.5 * (1 + std::tanh(s / width_)); };
    out[0] = z[1] / (m_.m1 + step(z[0] - m_.xa) * m_.m2);
    out[1] = -m_.k1 * (z[0] - m_.l1) - step(z[0] - m_.xb) * m_.k2 * (z[0] - m_.xb);
    return EvalStatus::ok;
  }

 private:
  Masses m_;
  double width_;
};

constexpr double kRtol = 1e-8;

template <class Model>
void run(benchmark::State& state, Model& model) {
  Masses m;
  MassesClosedForm exact(m);
  const double t_end = exact.t_contact + 0.9 * (exact.t_return - exact.t_contact);
  padae::Options options;
  options.rtol = kRtol;
  options.atol = 1e-10;
  options.time_scale = t_end;
  double error = 0;
  long steps = 0, rejected = 0;
  for (auto _ : state) {
    padae::Integrator integrator(model, options);
    if (!integrator.initialize(0.0, Vector{{0.0, 0.0}})) state.SkipWithError(integrator.failure().reason.c_str());
    while (integrator.time() < t_end)
      if (integrator.step(t_end).kind == padae::StepKind::failed) {
        state.SkipWithError(integrator.failure().reason.c_str());
        break;
      }
    error = std::abs(integrator.state()[0] - exact.position(t_end));
    steps = integrator.statistics().steps;
    rejected = integrator.statistics().rejected_error_test + integrator.statistics().rejected_newton;
  }
  state.counters["error"] = error;
  state.counters["steps"] = static_cast<double>(steps);
  state.counters["rejected"] = static_cast<double>(rejected);
}

void LogicalFunction(benchmark::State& state) {
  const double width = std::pow(10.0, -static_cast<double>(state.range(0)));
  MassesLogicalFunction model(Masses{}, width);
  state.SetLabel("eps=1e-" + std::to_string(state.range(0)));
  run(state, model);
}
BENCHMARK(LogicalFunction)->DenseRange(2, 8)->Unit(benchmark::kMillisecond);

void PredicateForm(benchmark::State& state) {
  padae::testing::MassesMomentum model(Masses{});
  state.SetLabel("predicates");
  run(state, model);
}
BENCHMARK(PredicateForm)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
