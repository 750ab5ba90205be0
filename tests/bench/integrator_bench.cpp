// Path samples per second of pt, bdpt and lt on the code-built Cornell box (tests/support/test_scenes.h)
// at 256x256, max depth 5 (segments), on every core: one iteration renders one sample per pixel, TBB
// parallel over rows of pixels. Counter "samples/s" (whole machine, wall clock) is the figure to compare
// with pbrt-v3 (~0.76 M/s pt, ~0.32 M/s bdpt on the 2-core machines here); the *OneThread variants
// give samples per CPU-second.
#include <benchmark/benchmark.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <memory>

#include "common/core/rng.h"
#include "common/integrators/evaluators.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

constexpr int kRes = 256;

void renderFrames(benchmark::State& state, std::string method, int maxDepth, bool parallel) {
  const auto scene = RenderScene::build(test::smallCornellBox(kRes, kRes));
  IntegratorSettings is;
  is.maxDepth = maxDepth;
  is.rrDepth = 5;
  const auto evaluator = makeEvaluator(*scene, method, is);
  uint64_t frame = 0;
  std::atomic<uint64_t> splats{0};
  for (auto _ : state) {
    auto row = [&](int y) {
      PathContribution c;
      IndependentSource source(0, 0);
      uint64_t count = 0;
      for (int x = 0; x < kRes; ++x) {
        source.reset(hashKeys(1, uint64_t(y) * kRes + uint64_t(x)), frame);
        const Vec2 pixel{float(x), float(y)};
        evaluator->evaluate(source, &pixel, c);
        count += c.splats.size();
      }
      splats += count;
    };
    if (parallel) {
      tbb::parallel_for(0, kRes, row);
    } else {
      for (int y = 0; y < kRes; y += 8) row(y);  // every 8th row: 1/8 frame per iteration
    }
    ++frame;
  }
  const double samples = double(frame) * kRes * kRes / (parallel ? 1 : 8);
  state.counters["samples/s"] = benchmark::Counter(samples, benchmark::Counter::kIsRate);
  state.counters["splats/sample"] = double(splats.load()) / samples;
}

void BM_PathTracer(benchmark::State& state) { renderFrames(state, "pt", int(state.range(0)), true); }
void BM_Bdpt(benchmark::State& state) { renderFrames(state, "bdpt", int(state.range(0)), true); }
void BM_LightTracer(benchmark::State& state) { renderFrames(state, "lt", int(state.range(0)), true); }
// One thread, CPU time: samples per CPU-second, robust to other processes sharing the machine
// (x cores gives the whole-machine figure when the machine is idle).
void BM_PathTracerOneThread(benchmark::State& state) { renderFrames(state, "pt", int(state.range(0)), false); }
void BM_BdptOneThread(benchmark::State& state) { renderFrames(state, "bdpt", int(state.range(0)), false); }

BENCHMARK(BM_PathTracer)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_Bdpt)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_LightTracer)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_PathTracerOneThread)->Arg(5)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_BdptOneThread)->Arg(5)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
}  // namespace mlt

BENCHMARK_MAIN();
