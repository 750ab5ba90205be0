// What one bootstrap candidate costs per path length (issue 9, "bootstrap at most 5% of the job"): mmlt's
// bootstrap evaluates candidates of every length k = 1..maxDepth, and its budgeted sizing (bootstrap.h)
// spends its doublings where b_k is least certain, which on the bundled scenes is the long lengths. If a
// candidate of length k costs more than one of length 1, a budget counted in candidates overruns in time.
// This measures it: ns per candidate of length k (IndependentSource::candidate, the method's own target,
// as bootstrapMarkovChainJob evaluates them), thread CPU time, on the bundled caustic-mirror and Cornell
// box at 256x256, depth 12. Also printed: the numbers each candidate drew (IndependentSource::reads), the
// ratio of its time to the mean over lengths, and the same ratio of the cost the budgeted sizing counts
// (kCandidateOverhead + numbers drawn; bootstrap.h), which should follow it.
// Run: build/tests/bootstrap_cost_bench
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <map>
#include <memory>
#include <string>

#include "common/job/mlt_job.h"
#include "common/mlt/bootstrap.h"
#include "common/methods/pss_method.h"
#include "common/mlt/target.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"
#include "common/scene/mitsuba_loader.h"

namespace mlt {
namespace {

constexpr int kRes = 256;
constexpr int kDepth = 12;

double threadNs() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e9 + double(ts.tv_nsec);
}

const RenderScene& bundledScene(const std::string& name) {
  static std::map<std::string, std::unique_ptr<RenderScene>> scenes;
  auto& s = scenes[name];
  if (!s) {
    SceneDesc desc = loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + name + ".xml");
    desc.camera.width = desc.camera.height = kRes;
    s = RenderScene::build(desc);
  }
  return *s;
}

std::map<std::string, std::map<int, double>> nsPerCandidate;  // scene -> k -> best ns
std::map<std::string, std::map<int, double>> readsPerCandidate;  // scene -> k -> mean numbers drawn

void candidates(benchmark::State& state, const std::string& sceneName) {
  const int k = int(state.range(0));
  const RenderScene& scene = bundledScene(sceneName);
  RenderSettings s;
  s.method = "mmlt";
  s.integrator.maxDepth = kDepth;
  s.width = s.height = kRes;
  const std::unique_ptr<PssTarget> target = findChainJobSpec("mmlt")->makeTarget(scene, s);
  PathContribution path;
  constexpr uint64_t kBatch = 4096;
  uint64_t index = uint64_t(k) << kCandidateSlotBits;
  double sink = 0, best = 1e300;
  uint64_t reads = 0, evaluated = 0;
  for (auto _ : state) {
    const double t0 = threadNs();
    for (uint64_t i = 0; i < kBatch; ++i) {
      IndependentSource source = IndependentSource::candidate(1, index++);
      target->evaluate(source, k, path);
      sink += targetFunction(path);
      reads += source.reads();
    }
    evaluated += kBatch;
    best = std::min(best, (threadNs() - t0) / double(kBatch));
  }
  benchmark::DoNotOptimize(sink);
  nsPerCandidate[sceneName][k] = best;
  readsPerCandidate[sceneName][k] = double(reads) / double(std::max<uint64_t>(evaluated, 1));
  state.counters["ns/candidate"] = best;
}

void BM_MmltCandidateCausticMirror(benchmark::State& s) { candidates(s, "caustic-mirror"); }
void BM_MmltCandidateCornellBox(benchmark::State& s) { candidates(s, "cornell-box"); }
BENCHMARK(BM_MmltCandidateCausticMirror)->DenseRange(1, kDepth)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MmltCandidateCornellBox)->DenseRange(1, kDepth)->Unit(benchmark::kMillisecond);

void printTable() {
  for (const auto& [scene, perK] : nsPerCandidate) {
    const std::map<int, double>& reads = readsPerCandidate[scene];
    double mean = 0, modelMean = 0;
    for (const auto& [k, ns] : perK) {
      mean += ns / double(perK.size());
      modelMean += (kCandidateOverhead + reads.at(k)) / double(perK.size());
    }
    std::printf("\n%s, mmlt, depth %d, %dx%d: ns per bootstrap candidate by path length k\n", scene.c_str(), kDepth,
                kRes, kRes);
    std::printf("%4s %10s %10s %12s %14s\n", "k", "ns", "numbers", "ns / mean", "cost / mean");
    for (const auto& [k, ns] : perK)
      std::printf("%4d %10.0f %10.1f %12.2f %14.2f\n", k, ns, reads.at(k), ns / mean,
                  (kCandidateOverhead + reads.at(k)) / modelMean);
  }
}

}  // namespace
}  // namespace mlt

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  mlt::printTable();
  benchmark::Shutdown();
  return 0;
}
