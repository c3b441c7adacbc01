// Parsing and elaborating a generated netlist of N elements: an RC ladder with sources, B
// sources, switches, diodes and subcircuit instances, so that every kind of card is timed.
// Run: netlist_bench --benchmark_filter=ParseAndElaborate
#include <benchmark/benchmark.h>
#include <malloc.h>

#include <string>

#include <fmt/format.h>

#include "netlist/netlist.hpp"

namespace {

// About `elements` flat elements (each X instance expands to 2).
std::string generate(int elements) {
  std::string text = "generated ladder\n.param rbase=1k cbase=1n\n"
                     ".subckt cell a b params: r=1k\nR1 a m {r}\nC1 m b 10p\n.ends\n"
                     ".model dm D(is=1e-14 n=1.5)\n.model sm SW(vt=0.5 vh=0.1 ron=1 roff=1meg)\n"
                     "V0 n0 0 PULSE(0 5 1n 1n 1n 1u 2u)\n";
  int count = 1;
  for (int i = 0; count < elements; ++i) {
    switch (i % 6) {
      case 0: text += fmt::format("R{0} n{0} n{1} {{rbase*1.01}}\n", i, i + 1); break;
      case 1: text += fmt::format("C{0} n{1} 0 {{cbase}} ic=0\n", i, i + 1); break;
      case 2: text += fmt::format("B{0} n{1} 0 I={{v(n{0}) > 1 ? 1m : 0}}\n", i, i + 1); break;
      case 3: text += fmt::format("D{0} n{0} n{1} dm\n", i, i + 1); break;
      case 4: text += fmt::format("S{0} n{0} n{1} n{0} 0 sm off\n", i, i + 1); break;
      case 5: text += fmt::format("X{0} n{0} n{1} cell r={{rbase}}\n", i, i + 1); ++count; break;
    }
    ++count;
  }
  return text + ".tran 1n 10u\n.end\n";
}

std::size_t heap_in_use() {
  struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;  // small blocks + mmapped large ones
}

void ParseAndElaborate(benchmark::State& state) {
  const std::string text = generate(static_cast<int>(state.range(0)));
  std::size_t elements = 0, heap = 0;
  for (auto _ : state) {
    std::size_t heap_before = heap_in_use();
    netlist::Diagnostics diagnostics;
    auto parsed = netlist::parse_text(text, "generated.cir", diagnostics);
    auto circuit = netlist::elaborate(parsed, diagnostics);
    if (!circuit) state.SkipWithError("the generated netlist has errors");
    heap = heap_in_use() - heap_before;  // AST + flat circuit, both alive here
    elements = circuit ? circuit->elements.size() : 0;
    benchmark::DoNotOptimize(circuit);
  }
  state.counters["elements"] = static_cast<double>(elements);
  state.counters["heap_bytes_per_element"] = static_cast<double>(heap) / static_cast<double>(elements);
  state.SetComplexityN(state.range(0));
}
BENCHMARK(ParseAndElaborate)
    ->RangeMultiplier(10)
    ->Range(1000, 100000)
    ->Unit(benchmark::kMillisecond)
    ->Complexity(benchmark::oN);

}  // namespace

BENCHMARK_MAIN();
