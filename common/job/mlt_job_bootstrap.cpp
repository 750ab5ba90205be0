// Markov chain jobs (mlt_job.h): the bootstrap. The direct light's choice (a pilot), the relative target's
// map, the candidates per path length (common/mlt/bootstrap.h), mmlt's b_1 from camera rays
// (emission_estimate.h), and with unlimited depth the lengths that still carry light.
#include "common/job/mlt_job.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "common/mlt/target.h"
#include "common/render/render_scene.h"

namespace mlt {

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

// DirectLight::Auto: the settings with the pilot's choice in its place (direct_light_rule.h); DirectLight::Separate
// without spp: the pilot that sizes the pass, in out.pilot. Otherwise the settings as they are.
RenderSettings resolveDirectLight(const ChainJobSpec& spec, const RenderScene& scene, const RenderSettings& settings,
                                  const MarkovChainBootstrap* earlier, MarkovChainBootstrap& out) {
  // The pilot decides, or an earlier bootstrap's pilot of the same seed, film and integrator did; the
  // bootstrap holds the choice, and the plan takes it from there.
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
  return resolved;
}

// The relative target's map (importance.h, floor > 0), before any candidate: their c reads it.
void makeImportanceMap(const ChainJobSpec& spec, const RenderScene& scene, const RenderSettings& s, double floor,
                       const MarkovChainBootstrap* earlier, MarkovChainBootstrap& out) {
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

// mmlt, rjmlt: length 1's estimate. b_1 from the camera rays e1 (emission_estimate.h, (E1)) where they estimated
// it (e1.estimated), else from the candidates, drawn again 4x at a time while every one missed a
// light the rays see; out.result's b and standard error follow. raySeconds: the rays' time (0 if reused).
void finishLengthOne(const ChainJobSpec& spec, const BootstrapConfig& bc, const BinnedCandidateFnFactory& candidates,
                     const TargetShape& shape, const EmissionEstimate& e1, bool reused, double raySeconds,
                     MarkovChainBootstrap& out) {
  const auto t0 = std::chrono::steady_clock::now();
  LengthBootstrap& l1 = out.result.lengths.front();
  const BootstrapEstimate counted = l1.estimate;  // what out.result.b and bStdErr hold for length 1
  if (e1.litCells > 0 && !(l1.estimate.b > 0)) {
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
                   e1.litCells, l1.c.size());
  }
  const double seconds = raySeconds + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.result.seconds += seconds;
  out.raySeconds = raySeconds;  // the candidates drawn again above are candidates' time
  BootstrapEstimate final = l1.estimate;
  if (e1.estimated) {
    final = e1.estimate;
    final.sampleVar = final.bulkVar = l1.estimate.sampleVar;  // a large step of length 1's variance
    if (shape.shaped()) {  // b_lum of length 1 from the same rays, unweighted
      const double var = l1.luminanceEstimate.sampleVar;
      l1.luminanceEstimate = e1.luminance;
      l1.luminanceEstimate.sampleVar = l1.luminanceEstimate.bulkVar = var;
    }
    spdlog::info("{}: b_1 = {:.6g} +- {:.2g} from {} camera rays ({}x{} cells per pixel, {} of them on a light's "
                 "outline with {} rays each; {}); the {} candidates of length 1 said {:.6g} +- {:.2g}",
                 spec.name(), final.b, final.stdErr, e1.rays, e1.cellsPerPixelAxis, e1.cellsPerPixelAxis,
                 e1.edgeCells, e1.edgeRays,
                 reused ? std::string("an earlier bootstrap's, not traced again") : fmt::format("{:.3f} s", seconds),
                 l1.c.size(), l1.estimate.b, l1.estimate.stdErr);
  } else {
    spdlog::info("{}: b_1 from the candidates: {} ({:.3f} s)", spec.name(),
                 e1.litCells == 0 ? std::string("the camera rays' pilot saw no light")
                                   : fmt::format("one cell of the camera rays' pilot holds {:.2g} of its emission, "
                                                 "a light a few pixels wide that rays sample badly", e1.maxCellShare),
                 seconds);
  }
  if (!(final.b == counted.b && final.stdErr == counted.stdErr)) {  // out.result's sums hold `counted`
    out.result.b += final.b - counted.b;
    out.result.bStdErr = std::sqrt(std::max(0.0, out.result.bStdErr * out.result.bStdErr -
                                                     counted.stdErr * counted.stdErr + final.stdErr * final.stdErr));
  }
  l1.estimate = final;
  if (e1.estimated) {  // the rays' count is fixed in advance: b_1 is developed from them, not the candidates
    l1.fixedCount = 0;
    l1.fixedEstimate = final;
    l1.fixedLuminanceEstimate = l1.luminanceEstimate;
  }
}

// Unlimited depth: one more block of lengths while the last one carried more than kNegligibleLengthShare of b
// (mlt_job.h). Each block's candidates have slots of their own.
void extendUnlimitedDepth(const ChainJobSpec& spec, BootstrapConfig bc, const BinnedCandidateFnFactory& candidates,
                          BootstrapResult& all) {
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
}

}  // namespace

MarkovChainBootstrap bootstrapMarkovChainJob(const ChainJobSpec& spec, const RenderScene& scene,
                                             const RenderSettings& settings, const MarkovChainBootstrap* earlier) {
  validateMarkovChainSettings(spec, settings);  // before the pilot reads the film size
  MarkovChainBootstrap out;
  // valid as `settings` was: a pass is chosen only where the method allows one
  const RenderSettings s = resolveDirectLight(spec, scene, settings, earlier, out);
  out.settings = s;
  out.settings.bootstrapSamples = int(bootstrapPerLength(spec, s));
  const std::vector<int> lengths = chainPathLengths(spec, s);
  if (lengths.empty()) {  // mmlt, separateDirect, max depth <= 2: the direct pass renders everything
    if (out.pilot) out.result.seconds = out.pilot->seconds;
    return out;
  }
  // The relative target's map (importance.h), before any candidate: their c reads it.
  const double floor = spec.importanceFloor(s);
  if (floor > 0) makeImportanceMap(spec, scene, s, floor, earlier, out);
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
  if (lengthOne) finishLengthOne(spec, bc, candidates, shape, *e1, reused, raySeconds, out);  // e1: traced or reused
  if (!spec.chainsPerLength() || s.integrator.maxDepth >= 0) return out;

  extendUnlimitedDepth(spec, bc, candidates, out.result);
  return out;
}

}  // namespace mlt
