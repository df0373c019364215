// Throughput of ftctune's elementary functions (sim_core/lanes/elementary.hpp) in scalar code and
// in SSE2, AVX2 and AVX-512 lanes: the seven functions of tests/lanes (sin, cos, exp, expm1,
// tanh, log, sig^a) over 4 096 arguments in [-3, 3], the range of attitude angles and scaled
// sliding variables. Items are arguments; time per item is the cost of all seven at one value.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "lanes/lane_functions.hpp"

namespace {

using LaneFn = void (*)(const double*, std::size_t, double*);

void run(benchmark::State& state, LaneFn fn, bool supported) {
  if (!supported) {
    state.SkipWithError("this CPU lacks the instruction set");
    return;
  }
  std::mt19937_64 g(1);
  std::uniform_real_distribution<double> d(-3.0, 3.0);
  std::vector<double> xs(4096), out(ftc::test::kLaneFunctions * xs.size());
  for (double& x : xs) x = d(g);
  for (auto _ : state) {
    fn(xs.data(), xs.size(), out.data());
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(xs.size()));
}

void BM_ElementaryScalar(benchmark::State& s) { run(s, ftc::test::lanes_scalar, true); }
void BM_ElementarySse2(benchmark::State& s) { run(s, ftc::test::lanes_sse2, true); }
void BM_ElementaryAvx2(benchmark::State& s) {
  run(s, ftc::test::lanes_avx2, __builtin_cpu_supports("avx2"));
}
void BM_ElementaryAvx512(benchmark::State& s) {
  run(s, ftc::test::lanes_avx512, __builtin_cpu_supports("avx512f"));
}

}  // namespace

BENCHMARK(BM_ElementaryScalar);
BENCHMARK(BM_ElementarySse2);
BENCHMARK(BM_ElementaryAvx2);
BENCHMARK(BM_ElementaryAvx512);
BENCHMARK_MAIN();
