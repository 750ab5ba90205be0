// The Markov-chain half of the job API: plan (bootstrap + chain allocation), run one chain, develop.
// Normalization is derived in common/mlt/develop.h; the chain loop is common/mlt/chain.h.
#include "common/job/mlt_job.h"

#include "common/job/emission_estimate.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "common/job/direct_light_rule.h"
#include "common/job/sample_job.h"
#include "common/mlt/bootstrap.h"
#include "common/mlt/chain.h"
#include "common/mlt/develop.h"
#include "common/mlt/kelemen_source.h"
#include "common/integrators/evaluators.h"
#include "common/mlt/pss_chain.h"
#include "common/mlt/target.h"
#include "common/render/render_scene.h"
#include "common/settings/direct_light_name.h"

namespace mlt {

namespace {

// Relative tolerance of the start-state replay check. The replay runs the same code on the same numbers,
// so it is bit-exact on one machine; the tolerance only absorbs a different compiler's float contraction.
constexpr double kReplayTolerance = 1e-5;

// Chains when settings.chains == 0: a function of the work only (never of the machine), so the plan and
// the image bits do not depend on where the coordinator runs. ~16k mutations per chain, 64..4096 chains.
uint64_t defaultChains(uint64_t totalMutations) {
  return std::clamp<uint64_t>(totalMutations / 16384, 64, 4096);
}

}  // namespace

bool isDirectUnit(const WorkUnit& u) { return u.mutations == 0 && u.sampleEnd > u.sampleBegin; }

int chainMinLength(const RenderSettings& s) { return directPassSegments(s) + 1; }

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

namespace {
// (D3)-(D5) per slot from the bootstrap's estimates and the large steps' sums (strata: the slot's (D6)
// strata, or none), and their total with the slots' standard errors in quadrature.
template <typename Strata>
RefinedB refineSlots(const std::vector<BootstrapEstimate>& boot, const std::vector<TargetSums>& large,
                     const Strata& strataOf) {
  RefinedB r;
  const size_t slots = std::max(boot.size(), large.size());
  r.perSlot.resize(slots);
  double var = 0;
  for (size_t l = 0; l < slots; ++l) {
    const TargetSums sums = l < large.size() ? large[l] : TargetSums{};
    const StratifiedMean strata = strataOf(l, sums);
    r.perSlot[l] = combineB(l < boot.size() ? boot[l] : BootstrapEstimate{}, sums, strata.valid ? &strata : nullptr);
    r.total.b += r.perSlot[l].b;
    r.total.samples += r.perSlot[l].samples;
    var += r.perSlot[l].stdErr * r.perSlot[l].stdErr;
  }
  r.total.stdErr = std::sqrt(var);
  return r;
}
}  // namespace

RefinedB refinedLuminanceB(const Normalization& norm, const ChainStats& merged) {
  return refineSlots(norm.bootstrapLuminance, merged.largeStepLuminanceSums,
                     [](size_t, const TargetSums&) { return StratifiedMean{}; });
}

RefinedB refinedB(const Normalization& norm, const ChainStats& merged, const Film* film) {
  return refineSlots(norm.bootstrapB, merged.largeStepSums, [film](size_t l, const TargetSums& large) {
    StratifiedMean strata;  // (D6), where the chains kept strata
    if (film && film->hasSplatLayer(bStrataLayer(l)) && large.n > 0)
      strata = postStratifiedMean(film->splatLayer(bStrataLayer(l)), film->width(), film->height());
    if (strata.valid && strata.n != large.n) strata.valid = false;  // every large step, once, or none
    return strata;
  });
}

namespace {



// Settings of the direct pass (separateDirect): kDirectPassMethod limited to directPassSegments.
JobPlan directPlan(const JobPlan& plan) {
  JobPlan d;
  d.settings = plan.settings;
  d.settings.method = kDirectPassMethod;
  d.settings.integrator.maxDepth = directPassSegments(plan.settings);
  return d;
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

namespace {
// Whether `earlier`'s b_1 camera rays are what emissionEstimate would compute for `s`: it reads the
// seed, the film and the integrator settings (emission_estimate.h).
// The same reads the direct-light pilot makes (direct_light_rule.h).
bool sameRaysInputs(const RenderSettings& e, const RenderSettings& s) {
  return e.seed == s.seed && e.width == s.width && e.height == s.height && e.integrator == s.integrator;
}
// The importance pilot's inputs are the rays' and its floor (importance_pilot.h); b_1's rays read its map.
bool importanceReusable(const MarkovChainBootstrap* earlier, const RenderSettings& s, double floor) {
  return earlier && earlier->importance && sameRaysInputs(earlier->settings, s) && earlier->importance->floor == floor;
}
// b_1's rays compute c of the target: its map and its power (target.h (T1)).
bool emissionReusable(const ChainJobSpec& spec, const MarkovChainBootstrap* earlier, const RenderSettings& s,
                      double floor) {
  const bool sameMap = floor > 0 ? importanceReusable(earlier, s, floor) : !(earlier && earlier->importance);
  return earlier && earlier->emission && sameRaysInputs(earlier->settings, s) && sameMap &&
         spec.targetPower(earlier->settings) == spec.targetPower(s);
}
}  // namespace

MarkovChainBootstrap bootstrapMarkovChainJob(const ChainJobSpec& spec, const RenderScene& scene,
                                             const RenderSettings& settings, const MarkovChainBootstrap* earlier) {
  validateMarkovChainSettings(spec, settings);  // before the pilot reads the film size
  MarkovChainBootstrap out;
  // DirectLight::Auto: the pilot decides (direct_light_rule.h), or an earlier bootstrap's pilot of the
  // same seed, film and integrator did; the bootstrap holds the choice, and the plan takes it from there.
  RenderSettings resolved = settings;
  // (Only a pilot run for the same use: one that only sized a pass measured no CV, and one that chose may
  // have stopped before the share's last samples, which a pass's size needs.)
  const auto runPilot = [&](PilotUse use) {
    if (earlier && earlier->pilot && sameRaysInputs(earlier->settings, settings) &&
        earlier->pilot->decided == (use == PilotUse::Decide)) {
      out.pilot = earlier->pilot;
      out.pilot->seconds = 0;  // not run again
    } else {
      out.pilot = directLightPilot(scene, settings, use);
    }
    return *out.pilot;
  };
  const auto pilotCost = [](const DirectLightPilot& p) {
    return p.seconds > 0 ? fmt::format("{:.3f} s", p.seconds) : std::string("an earlier bootstrap's pilot");
  };
  if (settings.directLight == DirectLight::Auto) {
    if (!spec.allowsSeparateDirect()) {
      resolved = withDirectLightChoice(settings, DirectLight::Chains);
    } else {
      const DirectLightPilot p = runPilot(PilotUse::Decide);
      DirectLight choice = p.separate ? DirectLight::Separate : DirectLight::Chains;
      // The lights seen directly by a pass where one is small on the film (kEmissionSppPerMutation: why).
      uint64_t smallLights = 0;
      if (choice == DirectLight::Chains && spec.allowsEmissionPass()) {
        const int G = emissionCellsPerPixelAxis(scene.camera().width(), scene.camera().height());
        smallLightCells(scene, G, &smallLights);
        if (smallLights > 0) choice = DirectLight::Emission;
      }
      resolved = withDirectLightChoice(settings, choice);
      const std::string chosen =
          choice == DirectLight::Separate ? fmt::format("by a {} pass (--direct-light separate)", kDirectPassMethod)
          : choice == DirectLight::Emission
              ? fmt::format("in the chains, but the lights seen directly by a {} pass, {} of them small on the film "
                            "(--direct-light emission)", kDirectPassMethod, smallLights)
              : std::string("in the chains (--direct-light chains)");
      spdlog::info("{}: direct light {}: the pilot's {} bdpt samples put {:.1f}% of the light in paths of at most {} "
                   "segments, {} (a pass is taken from {:.0f}% and up to a CV of {:.1f}; {})",
                   spec.name(), chosen,
                   p.samples, 100 * p.share, kDirectMaxSegments,
                   p.cv >= 0 ? fmt::format("their one-bounce light a CV of {:.2f} per sample", p.cv)
                             : std::string("too little for a pass (its CV not measured)"),
                   100 * kDirectMinShare, kDirectMaxCv, pilotCost(p));
    }
  } else if (settings.directLight == DirectLight::Separate && settings.spp == 0) {
    // The pass asked for, its size left to the plan: sized by the pilot's share like a chosen one (the plan
    // logs the share and the size).
    const DirectLightPilot p = runPilot(PilotUse::SizePass);
    spdlog::info("{}: the {} pass (--direct-light separate) is sized by a pilot of {} bdpt samples ({})", spec.name(),
                 kDirectPassMethod, p.samples, pilotCost(p));
  }
  const RenderSettings& s = resolved;  // valid as `settings` was: the pass is chosen only where allowed
  out.settings = s;
  out.settings.bootstrapSamples = int(bootstrapPerLength(spec, s));
  const std::vector<int> lengths = chainPathLengths(spec, s);
  if (lengths.empty()) {  // mmlt, separateDirect, max depth <= 2: the direct pass renders everything
    if (out.pilot) out.result.seconds = out.pilot->seconds;
    return out;
  }
  // The relative target's map (importance.h), before any candidate: their c reads it.
  const double floor = spec.importanceFloor(s);
  if (floor > 0) {
    if (importanceReusable(earlier, s, floor)) {
      out.importance = earlier->importance;
      out.importance->seconds = 0;  // not traced again
    } else {
      out.importance = importancePilot(scene, s, floor);
    }
    spdlog::info("{}: relative target (floor {:g} of the mean): {} from {} pt samples ({})", spec.name(), floor,
                 out.importance->map.empty()
                     ? std::string("no light seen, so the luminance target")
                     : fmt::format("an importance map of {}x{} tiles of {} pixels", out.importance->map.tilesX,
                                   out.importance->map.tilesY, out.importance->map.tileSize),
                 out.importance->samples,
                 out.importance->seconds > 0 ? fmt::format("{:.3f} s", out.importance->seconds)
                                             : std::string("an earlier bootstrap's, not traced again"));
  }
  const ImportanceMap* importance = out.importance && !out.importance->map.empty() ? &out.importance->map : nullptr;
  const TargetShape shape{importance, spec.targetPower(s)};
  if (shape.power != 1) spdlog::info("{}: tempered target, c = luminance^{:g} (target.h (T1))", spec.name(), shape.power);
  BootstrapConfig bc;
  bc.candidatesPerLength = uint64_t(out.settings.bootstrapSamples);
  bc.pathLengths = lengths;
  bc.luminance = shape.shaped();  // b_lum (develop.h (D8))
  if (bc.candidatesPerLength >= 4 * kCandidateGroups * 2) {
    // A budget of the cost of N mutations per length (bootstrap.h, chainMixCost: a candidate of a long
    // path costs more than one of a short path, and the chains dwell on bright paths, often short). A
    // quarter per length to start with, then the budget goes where b's variance is per unit of cost; one
    // length doubles while it fits. (mmlt's length 1, a small light seen directly, took most of it until
    // b_1 came from camera rays; now its candidates keep the first round's count.)
    bc.totalCandidates = bc.candidatesPerLength * lengths.size();
    bc.candidatesPerLength /= 4;
  }
  const uint64_t seed = s.seed;
  const int width = s.width, height = s.height;
  const BinnedCandidateFnFactory candidates = [&spec, &scene, &s, seed, width, height,
                                                shape]() -> BinnedCandidateFn {
    std::shared_ptr<PssTarget> target = spec.makeTarget(scene, s);
    auto path = std::make_shared<PathContribution>();
    return [target, path, seed, width, height, shape](uint64_t index, int k, CandidateInfo* info) {
      IndependentSource source = IndependentSource::candidate(seed, index);  // film positions spread evenly
      target->evaluate(source, k, *path);
      const double c = targetFunction(*path, shape);
      if (shape.shaped()) info->luminance = targetFunction(*path);  // b_lum (develop.h (D8))
      // mmlt: one splat per path; its allocation bin (pssmlt's single length needs none).
      if (c > 0 && !path->splats.empty()) info->bin = allocationBin(path->splats[0].pRaster, width, height);
      info->work = source.reads();
      return c;
    };
  };
  // mmlt and rjmlt take b_1 from camera rays (emission_estimate.h, (E1)) unless a light seen directly is a
  // few very bright pixels (kEmissionMaxCellShare of the pilot): then length 1's candidates only seed its
  // chains.
  const bool lengthOne = spec.chainsPerLength() && lengths.front() == 1;
  std::optional<EmissionEstimate> e1;
  double raySeconds = 0;
  const bool reused = lengthOne && emissionReusable(spec, earlier, s, floor);
  if (reused) {
    e1 = earlier->emission;  // the same rays' result: not traced again (raySeconds stays 0)
  } else if (lengthOne) {
    const auto t0 = std::chrono::steady_clock::now();
    e1 = emissionEstimate(scene, s, shape);
    raySeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  out.emission = e1;
  const bool raysForLengthOne = e1 && e1->estimated;
  // Length 1's candidates then only seed its chains and keep the first round's count, unless a small light
  // is seen (smallLightCells): its chains hardly move between lights (a large step from a light ~1 pixel
  // wide to another is accepted in proportion to their radiances), so the share of each light in the
  // image is the share of the chains that start there, drawn from the candidates; they need the count
  // their variance asks for (glossy-plates: with the first round's 23584 the smallest sphere's share was
  // off by +79% and the others' by -22 to -30% in a run at 240 mutations per pixel).
  if (raysForLengthOne && e1->smallLights == 0) bc.seedOnlyLengths = {1};
  if (e1 && bc.totalCandidates > 0) bc.spentCost = double(e1->rays) * kEmissionRayCost;  // the rays share the budget
  if (out.importance && bc.totalCandidates > 0) bc.spentCost += out.importance->cost;   // and the importance pilot
  out.result = runBinnedBootstrap(bc, candidates);
  if (out.pilot) out.result.seconds += out.pilot->seconds;  // the pilot is part of the bootstrap's cost
  if (out.importance) out.result.seconds += out.importance->seconds;
  if (lengthOne) {
    const auto t0 = std::chrono::steady_clock::now();
    LengthBootstrap& l1 = out.result.lengths.front();
    const BootstrapEstimate counted = l1.estimate;  // what out.result.b and bStdErr hold for length 1
    if (e1->litCells > 0 && !(l1.estimate.b > 0)) {
      // The rays see a light that every candidate of length 1 missed (a thin light on a small film): without
      // a candidate that carries light there is no chain of length 1 and the light would be missing from
      // the image. More candidates, 4x at a time, until one carries light.
      BootstrapConfig more = bc;
      more.pathLengths = {1};
      more.totalCandidates = 0;
      more.maxGrowth = 1;
      for (uint64_t n = 4 * l1.c.size(); n <= kMaxBootstrapPerLength && !(l1.estimate.b > 0); n *= 4) {
        more.candidatesPerLength = n;
        BootstrapResult r = runBinnedBootstrap(more, candidates);
        out.result.candidates += r.candidates - l1.c.size();  // their time is in `seconds` below
        l1 = std::move(r.lengths.front());
      }
      if (!(l1.estimate.b > 0))
        spdlog::warn("{}: camera rays see a light ({} lit cells of their pilot) that {} candidates of length 1 "
                     "missed: no chain renders it, and the image lacks it (raise --bootstrap)", spec.name(),
                     e1->litCells, l1.c.size());
    }
    const double seconds = raySeconds + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.result.seconds += seconds;
    out.raySeconds = raySeconds;  // the candidates drawn again above are candidates' time
    BootstrapEstimate final = l1.estimate;
    if (raysForLengthOne) {
      final = e1->estimate;
      final.sampleVar = final.bulkVar = l1.estimate.sampleVar;  // a large step of length 1's variance
      if (shape.shaped()) {  // b_lum of length 1 from the same rays, unweighted
        const double var = l1.luminanceEstimate.sampleVar;
        l1.luminanceEstimate = e1->luminance;
        l1.luminanceEstimate.sampleVar = l1.luminanceEstimate.bulkVar = var;
      }
      spdlog::info("{}: b_1 = {:.6g} +- {:.2g} from {} camera rays ({}x{} cells per pixel, {} of them on a light's "
                   "outline with {} rays each; {}); the {} candidates of length 1 said {:.6g} +- {:.2g}",
                   spec.name(), final.b, final.stdErr, e1->rays, e1->cellsPerPixelAxis, e1->cellsPerPixelAxis,
                   e1->edgeCells, e1->edgeRays,
                   reused ? std::string("an earlier bootstrap's, not traced again") : fmt::format("{:.3f} s", seconds),
                   l1.c.size(), l1.estimate.b, l1.estimate.stdErr);
    } else {
      spdlog::info("{}: b_1 from the candidates: {} ({:.3f} s)", spec.name(),
                   e1->litCells == 0 ? std::string("the camera rays' pilot saw no light")
                                     : fmt::format("one cell of the camera rays' pilot holds {:.2g} of its emission, "
                                                   "a light a few pixels wide that rays sample badly", e1->maxCellShare),
                   seconds);
    }
    if (!(final.b == counted.b && final.stdErr == counted.stdErr)) {  // out.result's sums hold `counted`
      out.result.b += final.b - counted.b;
      out.result.bStdErr = std::sqrt(std::max(0.0, out.result.bStdErr * out.result.bStdErr -
                                                       counted.stdErr * counted.stdErr + final.stdErr * final.stdErr));
    }
    l1.estimate = final;
  }
  if (!spec.chainsPerLength() || s.integrator.maxDepth >= 0) return out;

  // Unlimited depth: one more block of lengths while the last one carried more than
  // kNegligibleLengthShare of b (see mlt_job.h). Each block's candidates have slots of their own.
  BootstrapResult& all = out.result;
  double var = all.bStdErr * all.bStdErr;
  for (double blockB = all.b; blockB > kNegligibleLengthShare * all.b;) {
    const int next = all.lengths.back().pathLength + 1;
    if (next > kMaxUnlimitedLength) {
      spdlog::warn("{}, unlimited depth: paths longer than {} segments still carry {:.3g} of b; they are dropped",
                   spec.name(), kMaxUnlimitedLength, blockB / all.b);
      break;
    }
    bc.firstSlot = all.lengths.size();
    bc.pathLengths.clear();
    for (int k = next; k < next + kUnlimitedLengthBlock && k <= kMaxUnlimitedLength; ++k) bc.pathLengths.push_back(k);
    BootstrapResult block = runBinnedBootstrap(bc, candidates);
    for (LengthBootstrap& lb : block.lengths) all.lengths.push_back(std::move(lb));
    all.b += block.b;
    var += block.bStdErr * block.bStdErr;
    all.candidates += block.candidates;
    all.seconds += block.seconds;
    blockB = block.b;
  }
  all.bStdErr = std::sqrt(var);
  spdlog::info("{}, unlimited depth: path lengths {}..{} (the next {} carried less than {:.0e} of b)",
               spec.name(), all.lengths.front().pathLength, all.lengths.back().pathLength, kUnlimitedLengthBlock,
               kNegligibleLengthShare);
  return out;
}

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
  if (!(s.mutationsPerPixel > 0 && std::isfinite(s.mutationsPerPixel)))
    throw std::invalid_argument("settings: mutations per pixel must be > 0, got " + std::to_string(s.mutationsPerPixel));
  if (s.chains < 0) throw std::invalid_argument("settings: chains must be >= 0, got " + std::to_string(s.chains));
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
    norm.bootstrapB[slot] = lb.estimate;
    if (norm.target().shaped()) norm.bootstrapLuminance[slot] = lb.luminanceEstimate;
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
    JobPlan d = planSampleJob(directPlan(plan).settings);
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

PartialResult runDirectUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) {
  if (!isDirectUnit(unit)) throw std::invalid_argument("work unit " + std::to_string(unit.index) + " is not a sample batch of the direct pass");
  if (!separatesDirect(plan.settings)) throw std::invalid_argument("work unit " + std::to_string(unit.index) + " is a sample batch, but the plan has no direct pass");
  const JobPlan d = directPlan(plan);
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
  quantizeSums(st.largeStepSums[slot], s.seed, unit.index, uint64_t(slot));
  if (shape.shaped()) {
    st.largeStepLuminanceSums.assign(slot + 1, TargetSums{});
    st.largeStepLuminanceSums[slot] = counts.largeStepsLuminance;
    quantizeSums(st.largeStepLuminanceSums[slot], s.seed, unit.index, kLuminanceSumsKey + uint64_t(slot));
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::vector<Color> developMarkovChainImage(const JobPlan& plan, const PartialResult& merged) {
  if (merged.film.pixelCount() == 0) return developMarkovChainImage(plan, merged, {});  // zeros, or the error
  return developMarkovChainImage(plan, merged, markovChainLayerScales(plan, merged));
}

std::vector<Color> developMarkovChainImage(const JobPlan& plan, const PartialResult& merged,
                                           const std::vector<double>& scales) {
  const RenderSettings& s = plan.settings;
  const size_t P = size_t(s.width) * size_t(s.height);
  if (merged.film.pixelCount() == 0) {
    if (plan.units.empty()) return std::vector<Color>(P);  // b = 0: nothing carries light
    throw std::invalid_argument("developImage: no work units merged");
  }
  return merged.film.develop(scales);
}

namespace {
// (D8): each slot's chain and large-step layers scaled together so that the slot's image holds P b_lum^ of
// luminance, b_lum^ pooled from the bootstrap's luminance and the large steps' (refinedLuminanceB).
void scaleToLuminance(const Normalization& norm, const PartialResult& merged, std::vector<double>& scales) {
  const Film& film = merged.film;
  const double P = double(film.width()) * double(film.height());
  const RefinedB lum = refinedLuminanceB(norm, merged.stats);
  const size_t slots = norm.mutationsPerLength.size();
  const auto layerLuminance = [&](size_t layer) {  // sum over pixels, as luminance() weighs colours
    if (layer >= scales.size() || scales[layer] == 0 || !film.hasSplatLayer(layer)) return 0.0;
    const PixelBuffer& sums = film.splatLayer(layer);
    double total = 0;
    for (size_t i = 0; i < sums.size(); ++i)
      total += double(luminance(Color(1, 0, 0))) * sums[i].r + double(luminance(Color(0, 1, 0))) * sums[i].g +
               double(luminance(Color(0, 0, 1))) * sums[i].b;
    return total * scales[layer];
  };
  for (size_t slot = 0; slot < slots && slot < lum.perSlot.size(); ++slot) {
    const size_t chain = chainLayer(slot), large = largeStepLayer(slot, slots);
    const double developed = layerLuminance(chain) + layerLuminance(large);
    if (!(developed > 0) || !(lum.perSlot[slot].b > 0)) continue;  // nothing to scale (the image keeps its zeros)
    const double r = lum.perSlot[slot].b * P / developed;
    for (size_t layer : {chain, large})
      if (layer < scales.size()) scales[layer] *= r;
  }
}
}  // namespace

std::vector<double> markovChainLayerScales(const JobPlan& plan, const PartialResult& merged) {
  const RenderSettings& s = plan.settings;
  const size_t P = size_t(s.width) * size_t(s.height);
  // Layer 0: the direct pass's t = 1 splats, P / N with N the light paths of the direct units merged.
  uint64_t directLightPaths = 0;
  for (uint32_t i : merged.units)
    if (i < plan.units.size() && isDirectUnit(plan.units[i]))
      directLightPaths += uint64_t(plan.units[i].sampleEnd - plan.units[i].sampleBegin) * P;
  std::vector<double> scales(merged.film.splatLayerCount(), 0.0);
  if (directLightPaths > 0) scales[0] = double(P) / double(directLightPaths);
  // chainLayer(slot): (D2) with b_k pooled from bootstrap and large steps (D3) and M_k the mutations of that
  // length merged (all of them once every chain is in; a preview's are a subset, still exact per length).
  const RefinedB refined = refinedB(plan.norm, merged.stats, &merged.film);
  const auto& M = merged.stats.proposedPerLength;
  for (size_t slot = 0; slot < M.size() && chainLayer(slot) < scales.size(); ++slot)
    if (M[slot] > 0 && slot < refined.perSlot.size())
      scales[chainLayer(slot)] = chainSplatScale(refined.perSlot[slot].b, M[slot], P);
  // largeStepLayer(slot) (Kelemen MIS, (D7)): the b the chains weighted by, the bootstrap's, and the same M_k.
  const Normalization& norm = plan.norm;
  const size_t slots = norm.mutationsPerLength.size();
  for (size_t slot = 0; slot < M.size() && slot < slots && largeStepLayer(slot, slots) < scales.size(); ++slot)
    if (M[slot] > 0) scales[largeStepLayer(slot, slots)] = chainSplatScale(norm.weightB(slot), M[slot], P);
  if (norm.target().shaped()) scaleToLuminance(norm, merged, scales);  // (D8)
  return scales;
}

}  // namespace mlt
