// Markov chain jobs (mlt_job.h): one work unit. A chain (replay its start candidate, run the chain loop of
// common/mlt/chain.h, return its raw splat sums and statistics) or a sample batch of the direct pass.
#include "common/job/mlt_job.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "common/integrators/evaluators.h"
#include "common/job/sample_job.h"

namespace mlt {

bool isDirectUnit(const WorkUnit& u) { return u.mutations == 0 && u.sampleEnd > u.sampleBegin; }

RenderSettings directPassSettings(const RenderSettings& s) {
  RenderSettings d = s;
  d.method = kDirectPassMethod;
  d.integrator.maxDepth = directPassSegments(s);
  return d;
}

PartialResult runDirectUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) {
  if (!isDirectUnit(unit)) throw std::invalid_argument("work unit " + std::to_string(unit.index) + " is not a sample batch of the direct pass");
  if (!separatesDirect(plan.settings)) throw std::invalid_argument("work unit " + std::to_string(unit.index) + " is a sample batch, but the plan has no direct pass");
  JobPlan d;
  d.settings = directPassSettings(plan.settings);
  const auto evaluator = makeEvaluator(scene, d.settings.method, d.settings.integrator);
  // t = 1 splats in layer 0, developed with P / N. The lights seen directly: stratified pixel points, and
  // directPassMultiplicity (what the coordinator checks the counts against) times the samples in the
  // pixels a small light's footprint marks.
  PixelSampling sampling;
  if (plan.settings.directLight == DirectLight::Emission) {
    sampling.points = PixelSampling::Points::Hammersley;
    sampling.multiplicity = smallLightCells(scene, 1);
    const uint8_t outline = uint8_t(directPassMultiplicity(plan.settings));
    for (uint8_t& m : sampling.multiplicity) m = m ? outline : uint8_t(1);
  }
  PartialResult r = runSampleUnit(*evaluator, d, unit, nullptr, &sampling);
  r.samples = 0;  // samples count mutations in a Markov chain job
  return r;
}

PartialResult runMarkovChain(const ChainJobSpec& spec, const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) {
  const auto start = std::chrono::steady_clock::now();
  const RenderSettings& s = plan.settings;
  const Normalization& norm = plan.norm;

  if (isDirectUnit(unit)) return runDirectUnit(scene, plan, unit);

  if (unit.mutations == 0) throw std::invalid_argument("work unit " + std::to_string(unit.index) + " has no mutations");
  const int k = unit.pathLength;
  if (spec.chainsPerLength() != (k >= 1))
    throw std::invalid_argument("work unit " + std::to_string(unit.index) + ": path length " + std::to_string(k) +
                                " does not fit method " + s.method);
  const int slot = k < 0 ? 0 : k;
  if (slot >= int(norm.mutationsPerLength.size()) || norm.mutationsPerLength[slot] == 0)
    throw std::invalid_argument("work unit " + std::to_string(unit.index) + ": the plan has no mutations for path length " + std::to_string(k));
  const double bChain = norm.weightB(size_t(slot));  // Kelemen MIS weights only

  PartialResult result;
  result.units = {unit.index};
  KelemenSource source(kelemenParams(s), s.seed, unit.index, unit.startCandidate);
  const std::unique_ptr<PssTarget> target = spec.makeTarget(scene, s);

  // Replay the start candidate (iteration 0 of the source reads IndependentSource(seed, candidate)).
  PathContribution current, scratch;
  target->evaluate(source, k, current);
  const TargetShape shape = norm.target();
  const double c0 = targetFunction(current, shape);
  if (!(std::fabs(c0 - unit.startContribution) <= kReplayTolerance * std::fabs(unit.startContribution)) || !(c0 > 0))
    throw std::runtime_error(fmt::format(
        "chain replay mismatch: job seed {}, chain {}, candidate {}, path length {}: bootstrap recorded c = {:.17g}, "
        "replay gives c = {:.17g} (scene or code differs between coordinator and worker?)",
        s.seed, unit.index, unit.startCandidate, k, unit.startContribution, c0));
  source.accept();

  const std::unique_ptr<ChainState> state = spec.makeChainState(source, s, *target, k);
  PssChainTarget chainTarget(*target, source, k);
  SparseSplatter splatter(s.width, s.height, uint32_t(chainLayer(size_t(slot))));
  // b's strata (D6), for one-length methods only: mmlt's brightness error is its b_1's (the light seen
  // directly gets few large steps), where the strata did not help (docs/CHAINS.md), and they cost mmlt's
  // cheap mutations 10% of their throughput.
  const bool stratify = !spec.chainsPerLength();
  std::optional<SparseSplatter> strata;
  if (stratify) strata.emplace(s.width, s.height, uint32_t(bStrataLayer(size_t(slot))));
  const bool mis = s.splatting == MltSplatting::KelemenMIS;
  std::optional<SparseSplatter> largeSteps;  // (D7): scaled by the weights' b_k P / M_k at develop
  if (mis) largeSteps.emplace(s.width, s.height, uint32_t(largeStepLayer(size_t(slot), norm.mutationsPerLength.size())));
  SparseSink sink(splatter, strata ? &*strata : nullptr, largeSteps ? &*largeSteps : nullptr);  // b_k P / M_k (D2)
  ChainConfig config;
  config.splatting = mis ? ChainSplatting::KelemenMIS : ChainSplatting::ExpectedValue;
  config.largeStepProb = s.largeStepProb;
  config.b = bChain;
  config.tau = plan.norm.tailThreshold(size_t(slot));
  config.stratifyLargeSteps = stratify;
  config.target = shape;
  config.luminanceTau = norm.luminanceTailThreshold(size_t(slot));
  Pcg32 acceptRng = chainRng(s.seed, unit.index, 1);
  const ChainCounts counts = runChain(*state, chainTarget, config, sink, acceptRng, unit.mutations, current, c0, scratch);

  result.splats = splatter.take();
  if (strata) result.splats.layers.push_back(std::move(strata->take().layers.front()));  // bStrataLayer > chainLayer
  if (largeSteps) result.splats.layers.push_back(std::move(largeSteps->take().layers.front()));  // the last (D7)
  quantizeSplats(result.splats, s.seed, unit.index);
  result.samples = unit.mutations;
  ChainStats& st = result.stats;
  st.proposedPerLength.assign(slot + 1, 0);
  st.acceptedPerLength.assign(slot + 1, 0);
  const size_t kinds = spec.mutationKinds().size();
  st.proposedPerKind.assign(counts.proposed, counts.proposed + kinds);
  st.acceptedPerKind.assign(counts.accepted, counts.accepted + kinds);
  st.secondsPerKind.assign(counts.seconds, counts.seconds + kinds);
  static_assert(ChainStats::kKindStride == size_t(kMaxMutationKinds));
  st.proposedPerLengthKind.assign((slot + 1) * ChainStats::kKindStride, 0);
  st.acceptedPerLengthKind.assign((slot + 1) * ChainStats::kKindStride, 0);
  for (size_t kind = 0; kind < kinds; ++kind) {
    st.proposedPerLength[slot] += counts.proposed[kind];
    st.acceptedPerLength[slot] += counts.accepted[kind];
    st.proposedPerLengthKind[slot * ChainStats::kKindStride + kind] = counts.proposed[kind];
    st.acceptedPerLengthKind[slot * ChainStats::kKindStride + kind] = counts.accepted[kind];
  }
  st.largeStepSums.assign(slot + 1, TargetSums{});
  st.largeStepSums[slot] = counts.largeSteps;
  if (const uint64_t stride = bSampleStride(spec, s, norm, k); stride > 0) {
    // b_k's samples (develop.h (D9)): every technique of length k at fresh uniform points, from a stream of
    // their own (never the plan's candidates nor the chain's numbers), a count fixed by the plan.
    TargetSums b;
    const uint64_t streamSeed = hashKeys(s.seed, uint64_t(unit.index), 0x7262b5a3ULL);
    for (uint64_t i = 0, n = bSamplesFor(unit.mutations, stride); i < n; ++i) {
      IndependentSource source = IndependentSource::candidate(streamSeed, i);
      b.add(target->bSample(source, k));  // tau = infinity: the plan holds no bootstrap for this slot
    }
    st.largeStepSums[slot] = b;
  }
  quantizeSums(st.largeStepSums[slot], s.seed, unit.index, uint64_t(slot));
  if (shape.shaped()) {
    st.largeStepLuminanceSums.assign(slot + 1, TargetSums{});
    st.largeStepLuminanceSums[slot] = counts.largeStepsLuminance;
    quantizeSums(st.largeStepLuminanceSums[slot], s.seed, unit.index, kLuminanceSumsKey + uint64_t(slot));
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace mlt
