// veach-mlt job functions (see veach_job.h).
#include "common/methods/veach/veach_job.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "common/job/mlt_job.h"
#include "common/methods/veach/light_view.h"
#include "common/methods/veach/veach_chain.h"
#include "common/methods/veach/veach_method.h"
#include "common/mlt/chain.h"
#include "common/mlt/develop.h"
#include "common/mlt/kelemen_source.h"
#include "common/mlt/pss_chain.h"
#include "common/mlt/strata.h"
#include "common/mlt/target.h"
#include "common/render/render_scene.h"

namespace mlt::veach {

namespace {
constexpr int kStartTries = 16;  // a start strategy whose path evaluates to f = 0 is redrawn
// b refined as the job runs (develop.h (D3)-(D5)). Path-space chains make no large steps, so each chain also
// evaluates one independent bootstrap candidate (a bdpt sample: c(u) = lum of its MIS-weighted strategies,
// whose mean is b) per kMutationsPerBSample mutations, from a stream of its own (never the plan's
// candidates), and keeps their sums where the other methods keep their large steps' (largeStepSums), merged
// and quantized alike. A candidate costs ~3-8 mutations (VeachMltMethod::candidateCost), so this is ~8% of
// the chain's time; it lets the bootstrap stay at kBootstrapShare of the job and b still tighten with it.
// Their bulk is also kept per pixel of their camera coordinates (bStrataLayer(0)) and post-stratified when
// the image is developed (develop.h (D6)), as the large steps of the primary-sample chains.
constexpr uint64_t kMutationsPerBSample = 64;
// The bootstrap chose a candidate whose every strategy rebuilds to a path with f = 0 in path space (seen
// on door-ajar at 256x256: about one chain in 10^3, a connection through the door's gap that the path
// evaluator's geometry rejects). Such a path is not a state of this chain, so it cannot start one. The
// chain starts instead from a path resampled from fresh independent candidates in proportion to their c
// (importance resampling, as the bootstrap does), drawn from a stream of their own so the plan's candidates
// are untouched. The start only affects the chain's start-up bias (Veach 1997, sec. 11.3.2); b and the
// chain's weight are unchanged. Deterministic in (job seed, chain index); logged with both.
std::optional<StartPath> fallbackStart(const PathSpace& space, const RenderSettings& s, const WorkUnit& unit) {
  constexpr int kFallbackCandidates = 4096, kFallbackPool = 64;
  const uint64_t streamSeed = hashKeys(s.seed, uint64_t(unit.index), 0xfa11bac5ULL);
  Pcg32 pick = chainRng(s.seed, unit.index, 5);
  std::vector<StartPath> pool;
  double sum = 0;
  for (int i = 0; i < kFallbackCandidates && int(pool.size()) < kFallbackPool; ++i) {
    IndependentSource source = IndependentSource::candidate(streamSeed, uint64_t(i));
    std::optional<StartPath> sp = startPathFromSample(space, s.integrator, source, pick.uniformDouble());
    if (!sp || !(sp->candidateC > 0)) continue;
    sum += sp->candidateC;
    pool.push_back(std::move(*sp));
  }
  if (pool.empty())
    throw std::runtime_error(fmt::format(
        "veach-mlt: job seed {}, chain {}: neither candidate {} nor {} fresh candidates give a path with f > 0",
        s.seed, unit.index, unit.startCandidate, kFallbackCandidates));
  double u = pick.uniformDouble() * sum;
  size_t chosen = pool.size() - 1;
  for (size_t i = 0; i < pool.size(); ++i) {
    if (u < pool[i].candidateC) {
      chosen = i;
      break;
    }
    u -= pool[i].candidateC;
  }
  spdlog::warn("veach-mlt: job seed {}, chain {}: candidate {} has no strategy with f > 0 in path space; the chain "
               "starts from a path resampled from {} fresh candidates", s.seed, unit.index, unit.startCandidate,
               pool.size());
  return std::move(pool[chosen]);
}

}  // namespace

JobPlan planVeachJob(const RenderScene& scene, RenderSettings settings) {
  static const VeachMltMethod method;
  settings.method = method.name();
  method.validate(settings);
  PathSpace check(scene, settings.integrator.maxDepth);  // throws for unsupported lights
  (void)check;
  JobPlan plan = planMarkovChainJob(method, scene, settings);  // pssmlt-bdpt's bootstrap and allocation (veach_job.h)
  if (plan.norm.totalMutations > 0) return plan;
  const std::optional<RenderSettings> again = method.settingsWhenNoChains(settings);
  if (!again) return plan;
  // No path outside the light views carries light, so there is no chain to carry the light-view pass:
  // the chains carry those paths themselves (the same image in expectation).
  spdlog::warn("veach-mlt: job seed {}: no light reaches the camera except by light views (E S* L); planned "
               "again with veach-light-view 0, the chains carrying them", settings.seed);
  return planMarkovChainJob(method, scene, *again);
}

PartialResult runVeachChain(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit,
                            const MutationSettings& mutations) {
  const auto start = std::chrono::steady_clock::now();
  const RenderSettings& s = plan.settings;
  if (isDirectUnit(unit)) return runDirectUnit(scene, plan, unit);  // separateDirect: bdpt, as for every method
  if (unit.mutations == 0) throw std::invalid_argument("veach-mlt: work unit " + std::to_string(unit.index) + " has no mutations");
  const uint32_t sppLV = lightViewSpp(mutations.lightView, s.mutationsPerPixel);
  const PathSpace space(scene, s.integrator.maxDepth, chainMinLength(s), sppLV > 0);

  // Start: replay the candidate, then pick one of its strategies.
  Pcg32 pick = chainRng(s.seed, unit.index, 3);
  std::optional<StartPath> sp;
  for (int tries = 0; tries < kStartTries && !sp; ++tries) {
    IndependentSource source = IndependentSource::candidate(s.seed, unit.startCandidate);
    sp = startPathFromSample(space, s.integrator, source, pick.uniformDouble());
    if (!sp) continue;
    if (!(std::fabs(sp->candidateC - unit.startContribution) <= kReplayTolerance * std::fabs(unit.startContribution)))
      throw std::runtime_error(fmt::format(
          "veach-mlt chain replay mismatch: job seed {}, chain {}, candidate {}: bootstrap recorded c = {:.17g}, "
          "replay gives {:.17g}", s.seed, unit.index, unit.startCandidate, unit.startContribution, sp->candidateC));
  }
  if (!sp) sp = fallbackStart(space, s, unit);

  VeachChainState state(space, mutations, sp->path, chainRng(s.seed, unit.index, 4));
  VeachChainTarget target(state);
  PathContribution current, scratch;
  currentContribution(state, current);
  const double cx = targetFunction(current);

  PartialResult result;
  result.units = {unit.index};
  SparseSplatter splatter(s.width, s.height, uint32_t(chainLayer(0)));
  SparseSink sink(splatter);  // b P / M applied at develop (D1)
  ChainConfig config;                         // expected-value splatting
  Pcg32 acceptRng = chainRng(s.seed, unit.index, 1);
  const ChainCounts counts = runChain(state, target, config, sink, acceptRng, unit.mutations, current, cx, scratch);

  TargetSums bSamples;  // see kMutationsPerBSample
  SparseSplatter strata(s.width, s.height, uint32_t(bStrataLayer(0)));  // post-stratified by film position (D6)
  const double tau = plan.norm.tailThreshold(0);
  {
    static const VeachMltMethod method;
    const std::unique_ptr<PssTarget> candidate = method.makeTarget(scene, s);
    const uint64_t streamSeed = hashKeys(s.seed, uint64_t(unit.index), 0xb5a3b1e5ULL);
    for (uint64_t i = 0, n = veachBSamples(unit.mutations); i < n; ++i) {
      IndependentSource source = IndependentSource::candidate(streamSeed, i);
      candidate->evaluate(source, -1, scratch);
      const double c = targetFunction(scratch);
      bSamples.add(c, tau);
      const int camera = int(Stream::Camera);
      strata.addAt(strataPixel(source.valueAt(camera, 0), source.valueAt(camera, 1), s.width, s.height),
                   strataSample(std::min(c, tau)));
    }
  }

  std::optional<SparseSplatter> lightViews;
  if (sppLV > 0) {
    lightViews.emplace(s.width, s.height, uint32_t(lightViewLayer()));
    renderLightViews(space, plan, unit, sppLV, *lightViews);
  }

  result.splats = splatter.take();
  result.splats.layers.push_back(std::move(strata.take().layers.front()));  // bStrataLayer(0) > chainLayer(0)
  if (lightViews) {
    SparseSplats lv = lightViews->take();  // lightViewLayer() > bStrataLayer(0)
    result.splats.nonFinite += lv.nonFinite;
    result.splats.layers.push_back(std::move(lv.layers.front()));
  }
  quantizeSplats(result.splats, s.seed, unit.index);
  result.samples = unit.mutations;
  ChainStats& st = result.stats;
  st.proposedPerKind.assign(counts.proposed, counts.proposed + kNumKinds);
  st.acceptedPerKind.assign(counts.accepted, counts.accepted + kNumKinds);
  st.secondsPerKind.assign(counts.seconds, counts.seconds + kNumKinds);
  st.proposedPerLength.assign(1, 0);
  st.acceptedPerLength.assign(1, 0);
  for (int k = 0; k < kNumKinds; ++k) {
    st.proposedPerLength[0] += counts.proposed[k];
    st.acceptedPerLength[0] += counts.accepted[k];
  }
  st.largeStepSums.assign(1, bSamples);
  quantizeSums(st.largeStepSums[0], s.seed, unit.index, 0);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

uint64_t veachBSamples(uint64_t mutations) { return (mutations + kMutationsPerBSample - 1) / kMutationsPerBSample; }

std::vector<Color> developVeachImage(const JobPlan& plan, const PartialResult& merged, const MutationSettings& mutations) {
  if (merged.film.pixelCount() == 0) return developMarkovChainImage(plan, merged);  // zeros, or the error
  const uint32_t sppLV = lightViewSpp(mutations.lightView, plan.settings.mutationsPerPixel);
  std::vector<double> scales = markovChainLayerScales(plan, merged);
  if (sppLV > 0 && merged.film.splatLayerCount() > lightViewLayer()) {
    scales.resize(merged.film.splatLayerCount(), 0.0);
    scales[lightViewLayer()] = lightViewScale(plan, merged.units, sppLV);
  }
  return developMarkovChainImage(plan, merged, scales);
}

std::string acceptanceSummary(const ChainStats& stats) {
  std::string out;
  const auto& names = mutationKindNames();
  for (size_t k = 0; k < names.size() && k < stats.proposedPerKind.size(); ++k) {
    const uint64_t p = stats.proposedPerKind[k], a = k < stats.acceptedPerKind.size() ? stats.acceptedPerKind[k] : 0;
    if (!out.empty()) out += ", ";
    out += fmt::format("{} {:.3f} ({}/{})", names[k], p ? double(a) / double(p) : 0.0, a, p);
  }
  return out;
}

}  // namespace mlt::veach
