// Markov chains over primary samples as a job: bootstrap, chain allocation, one chain per work unit,
// development. Shared by every method of that kind (pssmlt, pssmlt-bdpt, mmlt; their folders under
// common/methods/ and the base class common/methods/pss_method.h): a method supplies a ChainJobSpec,
// its target function and its chain state, and this code does the rest the same way for all of them.
// Implemented in common/job/ (with common/mlt/), one file per step: mlt_job_settings.cpp (what a job resolves and
// checks first), mlt_job_bootstrap.cpp, mlt_job_plan.cpp (chain allocation), mlt_job_run.cpp (one work unit) and
// mlt_job_develop.cpp (b refined, the image).
#pragma once
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/job/direct_light_rule.h"
#include "common/job/emission_estimate.h"
#include "common/job/importance_pilot.h"
#include "common/job/job_types.h"
#include "common/mlt/allocation.h"
#include "common/mlt/bootstrap.h"
#include "common/mlt/chain.h"
#include "common/mlt/develop.h"
#include "common/mlt/kelemen_source.h"
#include "common/mlt/pss_chain.h"

namespace mlt {

class RenderScene;

// What a primary-sample chain method supplies.
class ChainJobSpec {
 public:
  virtual ~ChainJobSpec() = default;
  virtual std::string name() const = 0;
  // true: one path-length slot per length k (chainPathLengths), each with its own b_k and chains (mmlt);
  // false: one slot (index 0, path length -1) for all lengths.
  virtual bool chainsPerLength() const = 0;
  // Whether the target can leave out paths of at most kDirectMaxSegments segments (separateDirect).
  virtual bool allowsSeparateDirect() const = 0;
  // Whether a pass may render the lights seen directly instead (DirectLight::Emission: the target leaves
  // out paths of one segment); the default, allowsSeparateDirect. veach-mlt: no, its light-view pass
  // renders them already.
  virtual bool allowsEmissionPass() const { return allowsSeparateDirect(); }
  // The target function; one per thread of the bootstrap and one per chain.
  virtual std::unique_ptr<PssTarget> makeTarget(const RenderScene& scene, const RenderSettings& settings) const = 0;
  // The chain's state over its Kelemen source; its proposals' kinds index mutationKinds().
  virtual std::unique_ptr<ChainState> makeState(KelemenSource& source, const RenderSettings& settings) const = 0;
  // What the chain loop calls, after the start state was replayed through `target` and accepted. A state
  // that must see the chain's target and length (reversible jumps turn the target's current path back
  // into numbers) overrides this; the default is makeState(source, settings).
  virtual std::unique_ptr<ChainState> makeChainState(KelemenSource& source, const RenderSettings& settings,
                                                     PssTarget& target, int pathLength) const {
    (void)target;
    (void)pathLength;
    return makeState(source, settings);
  }
  virtual std::vector<std::string> mutationKinds() const = 0;
  // What one bootstrap candidate costs in the chain's mutations. The automatic bootstrap size is
  // kBootstrapShare of the mutations' time, so a count-sized bootstrap (--mutations-per-pixel) holds
  // kBootstrapShare * M / candidateCost candidates, as a --time budget sizes it by measured throughput.
  // 1: a candidate is one evaluation of the chain's own target (pssmlt, pssmlt-bdpt, mmlt, rjmlt).
  // The large-step probability when the settings leave it to the method (largeStepProb < 0).
  virtual float defaultLargeStepProb() const { return 0.3f; }
  // The splatting a job gets when its settings leave it to the method (MltSplatting::MethodDefault): Kelemen
  // MIS, measured better than expected values at equal time (docs/CHAINS.md); a method without large steps
  // (veach-mlt) overrides it, and refuses Kelemen MIS (supportsKelemenMis).
  virtual MltSplatting defaultSplatting() const { return MltSplatting::KelemenMIS; }
  virtual bool supportsKelemenMis() const { return true; }
  virtual double candidateCost(const RenderSettings& settings) const {
    (void)settings;
    return 1.0;
  }
  // What one of the chain's mutations costs in mmlt mutations: the direct pass gets this many times mmlt's
  // samples per mutation (directSppPerMutation), so that it takes the same share of a job's time whatever
  // the method. 1 unless a method measured otherwise.
  virtual double mutationCost() const { return 1.0; }
  // The settings to plan again with when the bootstrap finds nothing for the chains to carry (b = 0, no
  // chain); nullopt (the default): the job is rightly black. veach-mlt: its light-view pass off, since
  // without chains nothing would carry it (veach_job.h).
  virtual std::optional<RenderSettings> settingsWhenNoChains(const RenderSettings& settings) const {
    (void)settings;
    return std::nullopt;
  }
  // Mutations per Rao-Blackwellized b sample of path length k (PssTarget::bSample, develop.h (D9)): each chain
  // of length k draws ceil(mutations / this) of them, and b_k is refined by them instead of its large steps'
  // c. 0 (the default): by the large steps. Used only with the luminance target (a shaped target's
  // brightness comes from b_lum, develop.h (D8)); see bSampleStride.
  virtual uint64_t mutationsPerBSample(const RenderSettings& settings, int pathLength) const {
    (void)settings, (void)pathLength;
    return 0;
  }
  // The relative target's floor kappa (common/mlt/importance.h (R2)): > 0, the bootstrap makes an importance
  // map by a pilot (importance_pilot.h) and the target weights each splat's luminance by it; 0 (the
  // default), the target is the path's luminance. veach-mlt keeps 0: its chains compute their own target.
  virtual double importanceFloor(const RenderSettings& settings) const {
    (void)settings;
    return 0;
  }
  // The target's power beta (common/mlt/target.h (T1)): 1 (the default), c is linear in the path's light;
  // below 1, a tempered target. veach-mlt keeps 1.
  virtual double targetPower(const RenderSettings& settings) const {
    (void)settings;
    return 1;
  }
};

// The shortest path length a per-length method's chains cover: 1, or directPassSegments + 1 when the
// direct pass renders the shorter ones (separateDirect).
int chainMinLength(const RenderSettings& settings);

// Mutations per Rao-Blackwellized b sample of path length k in this plan (ChainJobSpec::mutationsPerBSample;
// develop.h (D9)): 0 where b_k is refined by the large steps (a shaped target, or the method has none).
// The plan and the chains of a job read the same number.
uint64_t bSampleStride(const ChainJobSpec& spec, const RenderSettings& settings, const Normalization& norm, int k);
// The b samples a chain of `mutations` draws at that stride.
inline uint64_t bSamplesFor(uint64_t mutations, uint64_t stride) { return stride ? (mutations + stride - 1) / stride : 0; }

// The bootstrap of a Markov chain job: a pure function of the scene and of the settings it reads (seed,
// method, width/height, integrator, directLight (Auto resolved by the pilot), bootstrapSamples resolved by
// bootstrapPerLength).
// The chain count, the mutation kernel and the large-step probability do not enter it, so one bootstrap
// serves plans with any of those (a time-budgeted render plans twice from one bootstrap, with its
// bootstrapSamples resolved first; see render_local.cpp).
struct MarkovChainBootstrap {
  // (Plans reuse a bootstrap of the same method only: checkBootstrapFits compares settings.method.)
  RenderSettings settings;  // the settings it was computed with (width/height, bootstrapSamples, directLight resolved)
  BootstrapResult result;   // result.seconds includes raySeconds
  double raySeconds = 0;    // of those, b_1's camera rays (emission_estimate.h): a cost that does not grow with the candidates
  // mmlt, rjmlt: those rays' estimate. A pure function of the scene, the seed, the film and the integrator
  // settings, so a second bootstrap of the same job (a --time budget's final one after its probe) takes it
  // instead of tracing the rays again (bootstrapMarkovChainJob's `earlier`).
  std::optional<EmissionEstimate> emission;
  // DirectLight::Auto: the pilot that chose settings.directLight (direct_light_rule.h); DirectLight::Separate
  // with spp 0: the pilot whose share sizes the pass (directSppPerMutation). Also a pure function of the
  // scene, the seed, the film and the integrator settings, so a second bootstrap takes it.
  std::optional<DirectLightPilot> pilot;
  // The relative target's pilot and map (ChainJobSpec::importanceFloor > 0), which the candidates' c and the
  // chains' target read; a pure function of the scene, the seed, the film, the integrator settings and the
  // floor, so a second bootstrap takes it. Its cost shares the bootstrap's budget (BootstrapConfig::spentCost).
  std::optional<ImportancePilot> importance;
};

// Bootstrap sizing. The bootstrap finds start states, allocates chains to path lengths and gives the
// first estimate of b, which every large step of every chain then refines (mlt/develop.h (D3)-(D5)).
// Its candidates spread their film positions evenly (sample_source.h), which makes one candidate worth
// ~30 large steps for b on a scene with a visible light: so it gets kBootstrapShare of the mutations (a
// candidate costs about what a mutation costs; ChainJobSpec::candidateCost otherwise), spread evenly over the path lengths and rounded down to
// a multiple of 64, at least kMinBootstrapPerLength per length (a length whose candidates all miss gets no
// chains) and at most kMaxBootstrapPerLength. That count is a budget in cost: the cost of that many of the
// chains' mutations per length (a candidate of length 12 can cost 12x one of length 1, counted by the
// numbers it draws: bootstrap.h, chainMixCost). Each length starts with a quarter of it and the rest of the
// cost goes, by doublings, to the lengths whose b_k is least certain per unit of cost (bootstrap.h,
// totalCandidates); a single length doubles while it fits. mmlt's b_1 camera rays share the budget
// (BootstrapConfig::spentCost). The target is at most 5% of the job's time; the share is 3% because the
// same job's bootstrap takes 0.13-0.21 s of wall time from run to run on this 2-core machine (timing
// noise of up to +-1.5% of a 4-s job), and the doublings land anywhere in the upper half of the budget
// (docs/CHAINS.md, "Bootstrap share: the chains' mix of lengths and b_1's rays").
constexpr double kBootstrapShare = 0.03;
constexpr uint64_t kMinBootstrapPerLength = 4096;
constexpr uint64_t kMaxBootstrapPerLength = uint64_t(1) << 20;
// Candidates per path length: settings.bootstrapSamples if set, else the automatic size above.
uint64_t bootstrapPerLength(const ChainJobSpec& spec, const RenderSettings& settings);
// As above, for a job expected to run `candidatesAffordable` bootstrap candidates in its bootstrap share
// (a time budget: measured throughput x budget x kBootstrapShare).
uint64_t bootstrapPerLengthFor(const ChainJobSpec& spec, const RenderSettings& settings, double candidatesAffordable);
// mmlt with unlimited depth (max depth -1): lengths are bootstrapped in blocks of kUnlimitedLengthBlock
// from kMin on, until a whole block carries at most kNegligibleLengthShare of b (as the bootstrap
// measures it), or kMaxUnlimitedLength is reached. Longer paths are left out: a bias of about that share,
// since b_k falls geometrically once paths bounce between surfaces of albedo < 1.
constexpr int kUnlimitedLengthBlock = 8;
constexpr double kNegligibleLengthShare = 1e-4;
constexpr int kMaxUnlimitedLength = 1024;
// The allocation of mutations to path lengths: common/mlt/allocation.h (allocationWeights).
// The chain's sample-source parameters from resolved settings (large-step probability, kernel; a
// large-step probability still left to the method is refused by KelemenSource: resolveChainSettings first).
KelemenParams kelemenParams(const RenderSettings& settings);
// The direct pass (separateDirect) renders paths of at most kDirectMaxSegments segments with this estimator:
// a path tracer with next-event estimation and MIS. A pt sample of two segments costs half of bdpt's (1.32 M
// against 0.63 M samples/s on the Cornell box, one thread), and what bdpt adds for such short paths (light
// paths splatted to the camera) carries little but noise under the large lights the pilot takes the pass
// for (direct_light_rule.h). With the size below, the pt pass beat session 31's bdpt pass (0.25 per mutation
// per pixel) in all 8 cells measured: mmlt and veach-mlt, 16 s, 256x256, 3 seeds, on the four bundled scenes
// where the pilot takes the pass, 0.71-0.84x (docs/CHAINS.md, "The direct pass: pt, twice as large").
inline constexpr const char* kDirectPassMethod = "pt";
// The direct pass's size when the settings leave it to the plan (separateDirect with spp = 0): pass samples
// (of at most kDirectMaxSegments segments) per mutation per pixel, times the mutations per pixel, rounded
// up, at least 1 (directSppFor). Per mutation, so that the image stays a pure function of (settings,
// mutations per pixel); the ratio (directSppPerMutation) is
//     r = mutationCost x kDirectSppPerShareOdds x min(s / (1 - s), kDirectMaxShareOdds),
// s the pilot's share of the light in the pass's paths (direct_light_rule.h), mutationCost the method's
// mutation in mmlt mutations (ChainJobSpec::mutationCost). The time the pass and the chains get is then
// in proportion to the share of the light each renders, t_pass / t_chains ~ s / (1 - s): the optimal
// split of a fixed time between two independent estimators of the two parts of a sum, when their noise
// relative to what each estimates falls alike with time (Neyman allocation with equal relative
// deviations). kDirectSppPerShareOdds is fitted to the Cornell box, whose best fixed ratio was 0.5 (share
// 0.765, odds 3.3); the other three bundled scenes that take the pass then get 0.39 (cornell-spheres, share
// 0.72), 0.78 (checker-spheres, 0.84) and 1.5 (textured-serialized, 0.91), where fixed ratios of 0.25,
// 0.5 and 1.0 had put each scene's best (docs/CHAINS.md, "The pass sized by the light it renders").
// Against the fixed 0.5, paired 16-s runs at 256x256: pssmlt-bdpt 0.68x (0.42x on textured-serialized),
// mmlt 0.71x and rjmlt 0.50x on textured-serialized, the other cells within the runs' noise. The
// odds are capped at kDirectMaxShareOdds (a share of 0.95), beyond what was measured. The bootstrap runs
// the pilot whenever the plan sizes a pass (--direct-light auto, or separate without --spp); without one
// (a plan from a bootstrap that had none) the ratio is mutationCost x kDirectSppPerMutation, the Cornell
// box's.
constexpr double kDirectSppPerShareOdds = 0.15;
constexpr double kDirectMaxShareOdds = 19;
constexpr double kDirectSppPerMutation = 0.5;
// The lights seen directly by a pass of their own (DirectLight::Emission; mmlt, rjmlt and pssmlt-bdpt, whose
// targets can leave out paths of one segment: ChainJobSpec::allowsEmissionPass). Chosen by the bootstrap (--direct-light auto) where the pilot keeps the direct
// light in the chains and a light is small on the film (emission_estimate.h, smallLightCells: its points
// land in at most kFootprintMaxCells cells). Why: length 1's chains hardly move from one light to another
// (a large step from a light a pixel wide to a larger one is accepted in proportion to their radiances, and
// small steps stay on the light), so each light's brightness in the image is the share of the chains that
// started on it: on glossy-plates (four spheres of equal power, radius 0.03 to 0.9) mmlt's spheres came out
// -87% to +79% off in single runs at 240 mutations per pixel, with b_1 itself right to 0.6%. A pt pass of one
// segment (a camera ray, Le where it lands) renders each pixel on its own, so no light takes another's
// light; it costs a ray a sample: kEmissionSppPerMutation samples per pixel per mutation per pixel (~3% of
// the job's time at mmlt's ~1 M mutations/s and ~4 M rays/s per thread) and the chains no longer spend
// mutations on length 1 (13% of glossy-plates' went there).
// The pass samples pixels at stratified points, and kEmissionOutlineSamples times as many in the pixels a
// small light's footprint marks (smallLightCells at one cell per pixel: the light and a ring of one pixel
// around it), where a sliver of a light ~1000 times brighter than its surroundings is the pass's error:
// at 7 samples per pixel (glossy-plates' 4-s work) one mmlt run of five held 52% of its relMSE in 4 such
// pixels. On glossy-plates the marks are ~200 of 65536 pixels: the pass costs ~5% more.
constexpr double kEmissionSppPerMutation = 0.125;
constexpr int kEmissionOutlineSamples = 16;
// The most samples a pixel of the direct pass takes per sample index: kEmissionOutlineSamples for
// Emission, else 1 (what a coordinator checks a partial film's pixel counts against).
inline int directPassMultiplicity(const RenderSettings& s) {
  return s.directLight == DirectLight::Emission ? kEmissionOutlineSamples : 1;
}
// Samples of the pass per mutation per pixel (directSppFor): mutationCost x kEmissionSppPerMutation for
// Emission; for Separate the rule above, from the pilot's share.
double directSppPerMutation(const ChainJobSpec& spec, const RenderSettings& settings, const DirectLightPilot* pilot);
int directSppFor(double sppPerMutation, double mutationsPerPixel);
// The settings with the method's defaults filled in where they were left to it (largeStepProb < 0,
// splatting). The direct pass's size (spp 0) is left to the plan, which has the pilot: directSppFor.
RenderSettings resolveChainSettings(const ChainJobSpec& spec, RenderSettings settings);
// Settings whose directLight is Auto with `chosen` (Chains or Separate) in its place, the one way Auto is
// resolved (the bootstrap's pilot, the plan, a time budget's sizing): an automatic pass is sized by the
// plan (spp 0, directSppFor) whatever spp the settings carried. Other settings are returned as they are.
RenderSettings withDirectLightChoice(RenderSettings settings, DirectLight chosen);
// The path lengths a job's chains cover ({-1} without chains per length; kMin..maxDepth with them; with
// unlimited depth the first block, to which the bootstrap adds).
std::vector<int> chainPathLengths(const ChainJobSpec& spec, const RenderSettings& settings);

// b per path length slot, pooled from the bootstrap and the large steps merged so far (develop.h (D3),
// (D4)); total = sum over slots, its standard error from the slots' in quadrature.
struct RefinedB {
  std::vector<BEstimate> perSlot;  // index = slot (pssmlt: 0; mmlt: k)
  BEstimate total;
};
// film (optional): the merged film, whose bStrataLayer(slot) layers post-stratify the large steps' bulk (D6).
RefinedB refinedB(const Normalization& norm, const ChainStats& merged, const Film* film = nullptr);
// With a shaped target (Normalization::target: a map or a power): b_lum per slot, the image's brightness, pooled from the
// bootstrap's luminance and the large steps' (develop.h (D3) for luminance, without strata; (D8)).
RefinedB refinedLuminanceB(const Normalization& norm, const ChainStats& merged);
// The quantization key of the large steps' luminance sums of a slot: kLuminanceSumsKey + slot (apart from
// their c sums' keys, slot).
constexpr uint64_t kLuminanceSumsKey = uint64_t(1) << 32;

// Throws std::invalid_argument naming the setting if a Markov chain job cannot be planned with these
// (resolved) settings, e.g. mmlt with unlimited depth. Cheap: the coordinator calls it at submission.
// The chain-family settings every Markov chain method reads (mutations per pixel > 0 and finite, chains
// >= 0, bootstrap samples 0 or >= 2); throws std::invalid_argument naming the setting.
void validateChainWorkSettings(const RenderSettings& settings);
void validateMarkovChainSettings(const ChainJobSpec& spec, const RenderSettings& settings);
// separateDirect: the method can leave out the direct light and the direct pass has spp >= 1 or 0 (sized
// by the plan, directSppFor); throws std::invalid_argument naming the setting.
void validateSeparateDirect(const ChainJobSpec& spec, const RenderSettings& settings);
// `earlier`: a bootstrap of the same scene whose b_1 camera rays (MarkovChainBootstrap::emission) are
// reused when its seed, film and integrator settings are these; the result is the same, bit for bit, and
// the rays are still charged to this bootstrap's budget (BootstrapConfig::spentCost), so that the size it
// resolves to reproduces the image without `earlier`. Its raySeconds is then 0: the rays took no time here.
MarkovChainBootstrap bootstrapMarkovChainJob(const ChainJobSpec& spec, const RenderScene& scene,
                                             const RenderSettings& settings,
                                             const MarkovChainBootstrap* earlier = nullptr);
// Chain allocation from an existing bootstrap: the same plan, bit for bit, as planMarkovChainJob(scene,
// settings). Throws std::invalid_argument naming the field if `settings` differs from the bootstrap's in
// a field the bootstrap reads.
JobPlan planMarkovChainJob(const ChainJobSpec& spec, const RenderScene& scene, const RenderSettings& settings,
                           const MarkovChainBootstrap& boot);
// Bootstrap (b, bk, candidates), chain allocation: a plan whose units are chains. settings.width/height
// are already resolved against the scene camera by planJob.
JobPlan planMarkovChainJob(const ChainJobSpec& spec, const RenderScene& scene, const RenderSettings& settings);
// A unit of the direct pass (separateDirect: sample batches appended after the chains) and how it runs:
// kDirectPassMethod (pt) with at most kDirectMaxSegments segments (pixel samples; a bdpt pass would add t = 1
// splats in layer 0).
bool isDirectUnit(const WorkUnit& unit);
// The direct pass's settings: kDirectPassMethod limited to directPassSegments.
RenderSettings directPassSettings(const RenderSettings& settings);
PartialResult runDirectUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit);
// Runs one chain (unit.startCandidate, unit.mutations, ...) and returns its raw splat sums + stats.
// It first replays its start candidate and checks that the c it gets is the bootstrap's, to this relative
// tolerance: the same code on the same numbers is bit-exact on one machine; the tolerance only absorbs a
// different compiler's float contraction between the coordinator and a worker.
constexpr double kReplayTolerance = 1e-5;
PartialResult runMarkovChain(const ChainJobSpec& spec, const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit);
// Normalization of the merged chains (b * P / M per length; see mlt/develop.h).
std::vector<Color> developMarkovChainImage(const JobPlan& plan, const PartialResult& merged);
// The splat layers' scales of that image (one per layer of merged.film; 0 for layers it does not develop),
// and the image with scales a method completed (veach-mlt's light-view layer).
std::vector<double> markovChainLayerScales(const JobPlan& plan, const PartialResult& merged);
std::vector<Color> developMarkovChainImage(const JobPlan& plan, const PartialResult& merged,
                                           const std::vector<double>& scales);

}  // namespace mlt
