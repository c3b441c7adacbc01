// The integrator alone on the Bari transistor amplifier: correct digits at t = 0.2 against run
// time, steps and factorizations, for a range of tolerances and both error norms.
#include <benchmark/benchmark.h>

#include "padae/integrator.hpp"
#include "transistor_amplifier.hpp"

namespace {

void TransistorAmplifier(benchmark::State& state) {
  const double rtol = std::pow(10.0, -static_cast<double>(state.range(0)));
  padae::Options options;
  options.rtol = rtol;
  options.atol = rtol;
  options.time_scale = 0.2;
  options.norm = state.range(1) ? padae::ErrorNorm::max : padae::ErrorNorm::rms;
  padae::testing::TransistorAmplifier model;
  double digits = 0;
  padae::Statistics statistics;
  for (auto _ : state) {
    padae::Integrator integrator(model, options);
    if (!integrator.initialize(0.0, padae::testing::TransistorAmplifier::initial_state()))
      state.SkipWithError(integrator.failure().reason.c_str());
    while (integrator.time() < 0.2)
      if (integrator.step(0.2).kind == padae::StepKind::failed) {
        state.SkipWithError(integrator.failure().reason.c_str());
        break;
      }
    digits = padae::testing::TransistorAmplifier::correct_digits(integrator.state());
    statistics = integrator.statistics();
  }
  state.SetLabel(std::string("rtol=1e-") + std::to_string(state.range(0)) + (state.range(1) ? " max" : " rms"));
  state.counters["digits"] = digits;
  state.counters["steps"] = static_cast<double>(statistics.steps);
  state.counters["rejected"] = static_cast<double>(statistics.rejected_error_test + statistics.rejected_newton);
  state.counters["lu"] = static_cast<double>(statistics.lu_factorizations);
}
BENCHMARK(TransistorAmplifier)->ArgsProduct({{4, 5, 6, 7, 8, 9, 10}, {0, 1}})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
