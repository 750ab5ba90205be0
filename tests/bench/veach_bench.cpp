// Veach's path-space chain, move by move (issue 12: "mutations per second reported per move"; issue 9,
// item 4, throughput toward the ray floor, applied to veach-mlt): on the bundled Cornell box and
// caustic-mirror at 256x256, the scenes' own depth, light views left to their pass as the method does.
//
// BM_Veach/<scene>/<move>: the chain loop as a job runs it (runChain: propose, f(y), T(x -> y) and
// T(y -> x), accept or reject, expected-value splats into a sink that drops them) with that move alone
// (its weight 1, the others 0); <scene>/all: every move by the default weights. The states: paths of bdpt
// samples (startPathFromSample on independent candidates, as a job's start minus the resampling), each
// run kBurnIn steps with every move; a move's kChains chains start from the first of them it applies to
// and keep their state from one iteration to the next. Counters:
//   proposals/s     proposals of that move per CPU second (process CPU time: one thread);
//   rays/proposal   closest-hit and shadow rays traced per proposal of that move (Accel's RayObserver);
//   shadow/proposal of which shadow rays;
//   acceptance      accepted / proposed of that move;
//   applicable      the share of steps in which the move applied (the others: an empty step, not counted).
// A move that applies to none of the states (the caustic perturbation on caustic-mirror, where every
// camera ray meets the mirror) is reported as skipped.
// Run: build/tests/veach_bench --benchmark_min_time=1
#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/methods/veach/veach_chain.h"
#include "common/mlt/chain.h"
#include "common/mlt/target.h"
#include "common/render/accel.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"
#include "common/scene/scene_loader.h"

namespace mlt {
namespace {

constexpr int kRes = 256;
constexpr size_t kChains = 16;
constexpr size_t kPool = 96;        // burnt-in states the moves' chains start from
constexpr uint64_t kBurnIn = 512;
constexpr uint64_t kSteps = 2048;  // per chain per iteration
constexpr uint64_t kSeed = 20261204;

class DropSink final : public ChainSink {
 public:
  void splat(const PathContribution&, double) override {}
};

struct Setup {
  std::unique_ptr<RenderScene> scene;
  IntegratorSettings integrator;
  std::unique_ptr<veach::PathSpace> space;
  std::vector<veach::Path> starts;
};

const Setup& setup(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Setup>> cache;
  std::unique_ptr<Setup>& s = cache[name];
  if (s) return *s;
  s = std::make_unique<Setup>();
  SceneDesc desc = loadScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + name + ".xml");
  desc.camera.width = desc.camera.height = kRes;
  s->integrator.maxDepth = desc.maxDepth.value_or(5);
  s->integrator.rrDepth = desc.rrDepth.value_or(5);
  s->scene = RenderScene::build(desc);
  s->space = std::make_unique<veach::PathSpace>(*s->scene, s->integrator.maxDepth, 1, /*withoutLightViews=*/true);
  DropSink sink;
  PathContribution current, scratch;
  for (uint64_t i = 0; s->starts.size() < kPool && i < 1000000; ++i) {
    IndependentSource source(kSeed, i);
    Pcg32 pick(kSeed, i);
    const std::optional<veach::StartPath> sp =
        veach::startPathFromSample(*s->space, s->integrator, source, pick.uniformDouble());
    if (!sp || !(luminance(s->space->f(sp->path, nullptr)) > 0)) continue;
    veach::VeachChainState chain(*s->space, veach::MutationSettings{}, sp->path, Pcg32(kSeed + 1, i));
    veach::VeachChainTarget target(chain);
    veach::currentContribution(chain, current);
    Pcg32 acceptRng(kSeed + 2, i);
    runChain(chain, target, ChainConfig{}, sink, acceptRng, kBurnIn, current, targetFunction(current), scratch);
    s->starts.push_back(chain.current());
  }
  if (s->starts.size() < kPool) throw std::runtime_error(name + ": too few start paths");
  return *s;
}

class RayCounter final : public RayObserver {
 public:
  void closestHit(const Ray&) override { ++closest; }
  void shadow(const Ray&) override { ++shadows; }
  uint64_t closest = 0, shadows = 0;
};

void runMove(benchmark::State& state, const std::string& sceneName, int move) {
  const Setup& su = setup(sceneName);
  veach::MutationSettings ms;
  if (move >= 0)
    for (int t = 0; t < veach::kNumKinds; ++t) ms.weight[t] = t == move ? 1.0 : 0.0;
  std::vector<std::unique_ptr<veach::VeachChainState>> chains;
  std::vector<Pcg32> acceptRngs;
  veach::MutationSettings every;  // every move on, so that the probe tells where each one applies
  for (double& w : every.weight) w = 1.0;
  const veach::VeachChainState probe(*su.space, every, su.starts[0], Pcg32());
  for (size_t c = 0; c < su.starts.size() && chains.size() < kChains; ++c) {
    if (move >= 0 && !(probe.choiceProbability(move, su.starts[c]) > 0)) continue;
    chains.push_back(std::make_unique<veach::VeachChainState>(*su.space, ms, su.starts[c], Pcg32(kSeed, 2 * c)));
    acceptRngs.emplace_back(kSeed, 2 * c + 1);
  }
  if (chains.empty()) {
    state.SkipWithError("the move applies to none of the states");
    return;
  }
  DropSink sink;
  RayCounter rays;
  RayObserver* previous = setThreadRayObserver(&rays);
  uint64_t steps = 0, proposed = 0, accepted = 0;
  PathContribution current, scratch;
  for (auto _ : state) {
    for (size_t c = 0; c < chains.size(); ++c) {
      veach::VeachChainTarget target(*chains[c]);
      veach::currentContribution(*chains[c], current);
      const ChainCounts counts =
          runChain(*chains[c], target, ChainConfig{}, sink, acceptRngs[c], kSteps, current, targetFunction(current), scratch);
      steps += kSteps;
      for (int t = 0; t < veach::kNumKinds; ++t) {
        if (move >= 0 && t != move) continue;
        proposed += counts.proposed[t];
        accepted += counts.accepted[t];
      }
    }
  }
  setThreadRayObserver(previous);
  const double p = double(std::max<uint64_t>(proposed, 1));
  state.counters["proposals/s"] = benchmark::Counter(double(proposed), benchmark::Counter::kIsRate);
  state.counters["rays/proposal"] = double(rays.closest + rays.shadows) / p;
  state.counters["shadow/proposal"] = double(rays.shadows) / p;
  state.counters["acceptance"] = double(accepted) / p;
  state.counters["applicable"] = double(proposed) / double(std::max<uint64_t>(steps, 1));
}

}  // namespace
}  // namespace mlt

int main(int argc, char** argv) {
  const std::vector<std::string> moves = mlt::veach::mutationKindNames();
  for (const char* scene : {"cornell-box", "caustic-mirror"}) {
    for (int move = -1; move < int(moves.size()); ++move) {
      const std::string name = std::string("BM_Veach/") + scene + "/" + (move < 0 ? "all" : moves[size_t(move)]);
      benchmark::RegisterBenchmark(name.c_str(), [scene = std::string(scene), move](benchmark::State& st) {
        mlt::runMove(st, scene, move);
      })->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
