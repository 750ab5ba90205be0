// Markov chain jobs (mlt_job.h): the settings a job resolves and checks before anything is traced, the path
// lengths its chains cover, the direct pass's size and the bootstrap's size.
#include "common/job/mlt_job.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mlt {

int chainMinLength(const RenderSettings& s) { return directPassSegments(s) + 1; }

uint64_t bSampleStride(const ChainJobSpec& spec, const RenderSettings& settings, const Normalization& norm, int k) {
  return norm.target().shaped() ? 0 : spec.mutationsPerBSample(settings, k);
}

std::vector<int> chainPathLengths(const ChainJobSpec& spec, const RenderSettings& s) {
  if (!spec.chainsPerLength()) return {-1};
  if (s.integrator.maxDepth == 0 || s.integrator.maxDepth < -1)
    throw std::invalid_argument("settings: " + spec.name() + " needs a max depth >= 1 or -1 (unlimited), got " +
                                std::to_string(s.integrator.maxDepth));
  // Unlimited: the first block; the bootstrap adds blocks while they carry light (bootstrapMarkovChainJob).
  const int kMin = chainMinLength(s);
  const int kMax = s.integrator.maxDepth < 0 ? kMin + kUnlimitedLengthBlock - 1 : s.integrator.maxDepth;
  std::vector<int> lengths;
  for (int k = kMin; k <= kMax; ++k) lengths.push_back(k);
  return lengths;
}

double directSppPerMutation(const ChainJobSpec& spec, const RenderSettings& s, const DirectLightPilot* pilot) {
  // One ray a sample; per mmlt mutation, so that the pass takes the same share of the time whatever the method.
  if (s.directLight == DirectLight::Emission) return spec.mutationCost() * kEmissionSppPerMutation;
  if (!pilot) return spec.mutationCost() * kDirectSppPerMutation;
  const double share = std::clamp(pilot->share, 0.0, 1.0);
  const double odds = share < 1 ? std::min(share / (1 - share), kDirectMaxShareOdds) : kDirectMaxShareOdds;
  return spec.mutationCost() * kDirectSppPerShareOdds * odds;
}

int directSppFor(double sppPerMutation, double mutationsPerPixel) {
  const double spp = std::ceil(sppPerMutation * mutationsPerPixel);
  return std::isfinite(spp) ? int(std::clamp(spp, 1.0, double(1 << 24))) : 1;
}

RenderSettings withDirectLightChoice(RenderSettings s, DirectLight chosen) {
  if (s.directLight != DirectLight::Auto) return s;
  s.directLight = chosen;
  if (separatesDirect(s)) s.spp = 0;  // an automatic pass is sized by the plan (directSppFor)
  return s;
}

RenderSettings resolveChainSettings(const ChainJobSpec& spec, RenderSettings s) {
  if (s.largeStepProb < 0) s.largeStepProb = spec.defaultLargeStepProb();
  if (s.splatting == MltSplatting::MethodDefault) s.splatting = spec.defaultSplatting();
  return s;
}

KelemenParams kelemenParams(const RenderSettings& s) {
  KelemenParams p;
  p.largeStepProb = s.largeStepProb;
  p.kernel = s.kernel == MutationKernel::Gaussian ? SmallStepKernel::Gaussian : SmallStepKernel::Kelemen;
  p.s1 = s.kelemenS1;
  p.s2 = s.kelemenS2;
  p.sigma = s.gaussianSigma;
  return p;
}

uint64_t bootstrapPerLengthFor(const ChainJobSpec& spec, const RenderSettings& s, double candidatesAffordable) {
  if (s.bootstrapSamples > 0) return uint64_t(s.bootstrapSamples);
  const double lengths = double(std::max<size_t>(chainPathLengths(spec, s).size(), 1));
  const double perLength = candidatesAffordable / lengths;
  // A multiple of 64: whole randomization groups, also for a quarter of it (budgeted sizing below).
  const double n = std::floor(std::min(perLength, double(kMaxBootstrapPerLength)) / 64) * 64;
  return std::max(kMinBootstrapPerLength, uint64_t(n));
}

uint64_t bootstrapPerLength(const ChainJobSpec& spec, const RenderSettings& s) {
  const double M = s.mutationsPerPixel * double(s.width) * double(s.height);
  return bootstrapPerLengthFor(spec, s, std::isfinite(M) && M > 0 ? kBootstrapShare * M / spec.candidateCost(s) : 0.0);
}

void validateChainWorkSettings(const RenderSettings& s) {
  if (!(s.mutationsPerPixel > 0 && std::isfinite(s.mutationsPerPixel)))
    throw std::invalid_argument("settings: mutations per pixel must be > 0, got " + std::to_string(s.mutationsPerPixel));
  if (s.chains < 0) throw std::invalid_argument("settings: chains must be >= 0, got " + std::to_string(s.chains));
  if (s.bootstrapSamples != 0 && s.bootstrapSamples < 2)
    throw std::invalid_argument("settings: bootstrap samples must be >= 2 (or 0: automatic), got " +
                                std::to_string(s.bootstrapSamples));
}

void validateMarkovChainSettings(const ChainJobSpec& spec, const RenderSettings& s) {
  if (s.method != spec.name())
    throw std::invalid_argument("settings: method is '" + s.method + "', not '" + spec.name() + "'");
  validateChainWorkSettings(s);
  if (s.width <= 0 || s.height <= 0) throw std::invalid_argument("settings: film size not resolved");
  if (s.integrator.maxDepth < -1) throw std::invalid_argument("settings: max depth must be >= -1 (-1 = unlimited)");
  if (s.integrator.rrDepth < 0) throw std::invalid_argument("settings: rr depth must be >= 0");
  validateSeparateDirect(spec, s);
  if (s.splatting == MltSplatting::KelemenMIS && !spec.supportsKelemenMis())
    throw std::invalid_argument("settings: " + spec.name() + " has no large steps to weight: Kelemen MIS splatting "
                                "(splatting = kelemen-mis) is not supported; use expected-value");
  chainPathLengths(spec, s);  // chains per length: a valid max depth
}

void validateSeparateDirect(const ChainJobSpec& spec, const RenderSettings& s) {
  if (!separatesDirect(s)) return;
  if (s.directLight == DirectLight::Emission && !spec.allowsEmissionPass())
    throw std::invalid_argument("settings: " + spec.name() + " cannot take direct light emission (a pass for the lights "
                                "seen directly): " + (spec.allowsSeparateDirect()
                                                          ? "its own light-view pass renders them; it takes chains or separate"
                                                          : "its splats do not carry the path length; it takes chains"));
  if (!spec.allowsSeparateDirect())
    throw std::invalid_argument("settings: " + spec.name() +
                                " cannot leave out the direct light (direct light separate): its splats do not carry the path length");
  if (s.spp < 0)
    throw std::invalid_argument("settings: the direct pass (direct light separate) needs spp >= 1 (or 0: sized by the "
                                "mutations per pixel), got " + std::to_string(s.spp));
}

}  // namespace mlt
