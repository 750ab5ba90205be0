// Markov chain jobs (mlt_job.h): the plan. Chain allocation from a bootstrap (mutations and chains per
// path length, start candidates by stratified resampling) and the direct pass's sample batches after the chains.
#include "common/job/mlt_job.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/job/sample_job.h"
#include "common/settings/direct_light_name.h"

namespace mlt {

namespace {

// Chains when settings.chains == 0: a function of the work only (never of the machine), so the plan and
// the image bits do not depend on where the coordinator runs. ~16k mutations per chain, 64..4096 chains.
uint64_t defaultChains(uint64_t totalMutations) {
  return std::clamp<uint64_t>(totalMutations / 16384, 64, 4096);
}

// The bootstrap reads these fields of the settings (see MarkovChainBootstrap); a plan may only reuse a
// bootstrap computed with the same values.
void checkBootstrapFits(const ChainJobSpec& spec, const RenderSettings& b, const RenderSettings& s) {
  auto differs = [](const char* field, auto was, auto now) {
    throw std::invalid_argument(fmt::format("settings: {} is {} but the bootstrap was computed with {}", field,
                                            now, was));
  };
  if (b.method != s.method) differs("method", b.method, s.method);
  if (b.seed != s.seed) differs("seed", b.seed, s.seed);
  if (b.width != s.width || b.height != s.height)
    differs("film size", fmt::format("{}x{}", b.width, b.height), fmt::format("{}x{}", s.width, s.height));
  if (b.integrator.maxDepth != s.integrator.maxDepth) differs("max depth", b.integrator.maxDepth, s.integrator.maxDepth);
  if (b.integrator.rrDepth != s.integrator.rrDepth) differs("rr depth", b.integrator.rrDepth, s.integrator.rrDepth);
  if (b.integrator.heuristic != s.integrator.heuristic)
    differs("MIS heuristic", int(b.integrator.heuristic), int(s.integrator.heuristic));
  if (b.directLight != s.directLight) differs("directLight", directLightName(b.directLight), directLightName(s.directLight));
  if (spec.importanceFloor(b) != spec.importanceFloor(s))
    differs("the relative target's floor", spec.importanceFloor(b), spec.importanceFloor(s));
  if (spec.targetPower(b) != spec.targetPower(s)) differs("the target's power", spec.targetPower(b), spec.targetPower(s));
  if (bootstrapPerLength(spec, b) != bootstrapPerLength(spec, s))
    differs("bootstrap samples per length", bootstrapPerLength(spec, b), bootstrapPerLength(spec, s));
}

}  // namespace

JobPlan planMarkovChainJob(const ChainJobSpec& spec, const RenderScene& scene, const RenderSettings& settings) {
  return planMarkovChainJob(spec, scene, settings, bootstrapMarkovChainJob(spec, scene, settings));
}

JobPlan planMarkovChainJob(const ChainJobSpec& spec, const RenderScene& /*scene*/, const RenderSettings& settings,
                           const MarkovChainBootstrap& bootstrap) {
  // Auto: as the bootstrap decided (bootstrapMarkovChainJob). The plan holds the values used.
  RenderSettings s = resolveChainSettings(spec, withDirectLightChoice(settings, bootstrap.settings.directLight));
  if (separatesDirect(s) && s.spp == 0) {  // the pass sized by the plan: by the pilot's share where there is one
    const DirectLightPilot* pilot = bootstrap.pilot ? &*bootstrap.pilot : nullptr;
    const double r = directSppPerMutation(spec, s, pilot);
    s.spp = directSppFor(r, s.mutationsPerPixel);
    spdlog::info("{}: the {} pass{} gets {} samples per pixel: {:.3g} per mutation per pixel ({})", spec.name(),
                 kDirectPassMethod, s.directLight == DirectLight::Emission ? " of the lights seen directly" : "",
                 s.spp, r,
                 s.directLight == DirectLight::Emission
                     ? fmt::format("kEmissionSppPerMutation; mutation cost {:g}", spec.mutationCost())
                     : fmt::format("{}; mutation cost {:g}",
                                   pilot ? fmt::format("the pilot's share {:.1f}% of the light", 100 * pilot->share)
                                         : std::string("no pilot"),
                                   spec.mutationCost()));
  }
  validateChainWorkSettings(s);
  KelemenSource validate(kelemenParams(s), 0, 0, 0);  // throws on bad kernel parameters
  checkBootstrapFits(spec, bootstrap.settings, s);

  JobPlan plan;
  plan.settings = s;
  plan.settings.bootstrapSamples = bootstrap.settings.bootstrapSamples;  // resolved
  const uint64_t P = uint64_t(s.width) * uint64_t(s.height);
  const uint64_t M = std::max<uint64_t>(1, static_cast<uint64_t>(std::llround(s.mutationsPerPixel * double(P))));
  const BootstrapResult& boot = bootstrap.result;
  Normalization& norm = plan.norm;
  norm.b = boot.b;
  norm.bStdErr = boot.bStdErr;
  norm.bootstrapSamples = boot.candidates;
  norm.bootstrapSeconds = boot.seconds;
  if (bootstrap.pilot && settings.directLight == DirectLight::Auto) {  // the pilot chose (else it only sized the pass)
    norm.directShare = bootstrap.pilot->share;
    norm.directCv = bootstrap.pilot->cv;
  }
  norm.totalMutations = boot.b > 0 ? M : 0;
  if (bootstrap.importance) norm.importance = bootstrap.importance->map;
  norm.targetPower = spec.targetPower(s);

  // ---- chain allocation: mutations M_k and chains C_k by mutationWeights (common/mlt/allocation.h; the plain rule,
  // proportional to b_k, for one length), largest remainder ----
  const std::vector<double> weights = mutationWeights(boot.lengths);
  const std::vector<uint64_t> Mk = boot.b > 0 ? apportion(M, weights) : std::vector<uint64_t>(weights.size(), 0);
  const uint64_t C = std::min<uint64_t>(s.chains > 0 ? uint64_t(s.chains) : defaultChains(M), M);
  std::vector<uint64_t> Ck = boot.b > 0 ? apportion(C, weights) : std::vector<uint64_t>(weights.size(), 0);
  if (spec.chainsPerLength()) {
    const int kMax = boot.lengths.empty() ? 0 : boot.lengths.back().pathLength;  // unlimited depth: as bootstrapped
    norm.bk.assign(kMax + 1, 0);
    norm.bkStdErr.assign(kMax + 1, 0);
    norm.mutationsPerLength.assign(kMax + 1, 0);
  } else {
    norm.mutationsPerLength.assign(1, 0);
  }
  norm.bootstrapB.assign(norm.mutationsPerLength.size(), BootstrapEstimate{});
  if (norm.target().shaped()) norm.bootstrapLuminance.assign(norm.mutationsPerLength.size(), BootstrapEstimate{});
  uint32_t index = 0;
  for (size_t l = 0; l < boot.lengths.size(); ++l) {
    const LengthBootstrap& lb = boot.lengths[l];
    const int slot = lb.pathLength < 0 ? 0 : lb.pathLength;
    if (spec.chainsPerLength()) {
      norm.bk[slot] = lb.estimate.b;
      norm.bkStdErr[slot] = lb.estimate.stdErr;
    }
    norm.mutationsPerLength[slot] = Mk[l];
    if (bSampleStride(spec, s, norm, lb.pathLength) == 0) {
      norm.bootstrapB[slot] = lb.fixedEstimate;  // unbiased (bootstrap.h): the image's b starts from it
      norm.bootstrapSamplesInB += lb.fixedCount;
    }  // else b_k comes from the chains' Rao-Blackwellized b samples alone (develop.h (D9))
    if (norm.target().shaped()) norm.bootstrapLuminance[slot] = lb.fixedLuminanceEstimate;
    if (Mk[l] == 0) continue;
    const uint64_t chains = std::clamp<uint64_t>(Ck[l], 1, Mk[l]);
    for (uint64_t j = 0; j < chains; ++j) {
      WorkUnit u;
      u.index = index++;
      u.pathLength = lb.pathLength;
      u.mutations = Mk[l] / chains + (j < Mk[l] % chains ? 1 : 0);
      // Start candidate: stratified resampling over the alias table, jittered by the chain's own stream.
      Pcg32 rng = chainRng(s.seed, u.index, 2);
      const double uStart = (double(j) + rng.uniformDouble()) / double(chains);
      u.startCandidate = lb.firstCandidate + lb.table.sample(std::min(uStart, 1.0 - 0x1p-53));
      u.startContribution = lb.c[u.startCandidate - lb.firstCandidate];
      plan.units.push_back(u);
    }
  }
  plan.settings.chains = static_cast<int>(index);

  // ---- direct illumination pass (separateDirect): pt sample batches after the chains ----
  if (separatesDirect(s)) {
    JobPlan d = planSampleJob(directPassSettings(plan.settings));
    for (WorkUnit u : d.units) {
      u.index = index++;
      plan.units.push_back(u);
    }
    plan.settings.samplesPerUnit = d.settings.samplesPerUnit;
  }
  spdlog::info("{}: bootstrap b = {:.6g} +- {:.3g} ({} candidates, {:.3f} s; {}), {} "
               "chains, {} mutations ({} per pixel){}",
               s.method, norm.b, norm.bStdErr, norm.bootstrapSamples, norm.bootstrapSeconds,
               "refined as the chains run",
               plan.settings.chains, norm.totalMutations, s.mutationsPerPixel,
               separatesDirect(s) ? fmt::format(", {} by {}", s.directLight == DirectLight::Emission
                                                                  ? "the lights seen directly" : "direct light",
                                                kDirectPassMethod)
                                  : std::string());
  return plan;
}

}  // namespace mlt
