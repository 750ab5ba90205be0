// Mutations per second of mmlt and pssmlt-bdpt on the code-built Cornell box (tests/support/test_scenes.h)
// at 256x256, max depth 5 and 8, through the job API (runWorkUnit: the chain loop, KelemenSource, the
// evaluator and the film splats). The plan (bootstrap) is made once outside the timed loop; one
// iteration runs a batch of chains.
//   BM_*Machine: chains in parallel (TBB) on every core, wall clock -> counter "mutations/s" is the
//                whole-machine figure (reference: ~2.1 M/s at depth 5 for two mature renderers).
//   BM_*OneThread: one chain at a time, process CPU time -> "mutations/s" is per CPU-second
//                (reference: ~2.2 M per CPU-second at depth 8).
#include <benchmark/benchmark.h>
#include <tbb/parallel_for.h>

#include <memory>

#include "common/methods/registry.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

constexpr int kRes = 256;

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(kRes, kRes));
  return *scene;
}

JobPlan makePlan(std::string m, int maxDepth) {
  RenderSettings s;
  s.method = m;
  s.directLight = DirectLight::Chains;  // the chains over every length, as the reference figures count them
  s.integrator.maxDepth = maxDepth;
  s.mutationsPerPixel = 16;  // 1M mutations in 64 chains of 16384 (the default chain length)
  s.chains = 64;
  s.bootstrapSamples = 20000;
  return planJob(cornell(), s);
}

void runChains(benchmark::State& state, std::string m, bool parallel) {
  const JobPlan plan = makePlan(m, int(state.range(0)));
  const size_t n = parallel ? plan.units.size() : 2;
  uint64_t mutations = 0, accepted = 0;
  for (auto _ : state) {
    std::vector<PartialResult> parts(n);
    if (parallel) tbb::parallel_for(size_t(0), n, [&](size_t i) { parts[i] = runWorkUnit(cornell(), plan, plan.units[i]); });
    else for (size_t i = 0; i < n; ++i) parts[i] = runWorkUnit(cornell(), plan, plan.units[i]);
    for (const PartialResult& p : parts) {
      mutations += p.samples;
      for (uint64_t a : p.stats.acceptedPerKind) accepted += a;
    }
  }
  state.counters["mutations/s"] = benchmark::Counter(double(mutations), benchmark::Counter::kIsRate);
  state.counters["acceptance"] = mutations ? double(accepted) / double(mutations) : 0.0;
}

void BM_MmltMachine(benchmark::State& s) { runChains(s, "mmlt", true); }
void BM_PssmltBdptMachine(benchmark::State& s) { runChains(s, "pssmlt-bdpt", true); }
void BM_MmltOneThread(benchmark::State& s) { runChains(s, "mmlt", false); }
void BM_PssmltBdptOneThread(benchmark::State& s) { runChains(s, "pssmlt-bdpt", false); }

BENCHMARK(BM_MmltMachine)->Arg(5)->Arg(8)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PssmltBdptMachine)->Arg(5)->Arg(8)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MmltOneThread)->Arg(5)->Arg(8)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();
BENCHMARK(BM_PssmltBdptOneThread)->Arg(5)->Arg(8)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

}  // namespace
}  // namespace mlt

BENCHMARK_MAIN();
