// What a Markov chain render reports (issue 3, "prints b with its standard error, the acceptance rate and
// mutations per second"): b +- SE as developed (bootstrap and the chains' large steps pooled), per path length k (mmlt) b_k +- SE, chains, mutations
// M_k and acceptance, and the acceptance of large and small steps. The report is written into the image
// metadata (addChainMetadata) and read back from it (chainReportFromMetadata), so `mltfarm render` prints
// the same summary whether the image was rendered in this process or fetched from the farm.
//
// Metadata keys (numbers; all are functions of the plan and the chains, never of the wall clock):
//   b, bStdErr (pooled from bootstrap and large steps: the b the image was developed with; with a relative
//   target, common/mlt/importance.h, the luminance b_lum each length is scaled to, develop.h (D8)), bBootstrap,
//   bBootstrapStdErr, bSamples, bootstrapSamples, bootstrapSamplesInB (those b holds: bootstrap.h, fixedCount),
//   bSampleEvery (written only where b samples refined b: develop.h (D9)),
//   bootstrapPerLength, chains, mutations, mutationsPerPixel (the setting: rendering again with
//   --mutations-per-pixel equal to it reproduces the image), acceptance, per mutation kind NAME (named
//   by the method, e.g. large, small): NAMESteps and acceptanceName (capitalized: acceptanceLarge),
//   largeStepProb, separateDirect (0/1: the plan's choice) and with it directSpp (the pass's samples
//   per pixel), with --direct-light auto the pilot's
//   directLightShare and directLightCv (common/job/direct_light_rule.h), kernelS1 + kernelS2 or kernelSigma;
//   mmlt per path length k: b<k>, bStdErr<k>, chains<k>, mutations<k>, acceptance<k>.
// Wall-clock keys, written only where the image may depend on the run (`mltfarm render --in-process`, by
// addMoveSecondsMetadata; never by the farm, whose images are byte-identical from run to run): per kind
// NAMESeconds, the wall time of its steps summed over chains (chain.h kMoveTimingStride), so that
// NAMESteps / NAMESeconds is the kind's mutations per second on one thread.
// Strings: kernel ("kelemen" | "gaussian"), splatting ("expected-value" | "kelemen-mis"), mutationKinds
// (the kind names, comma-separated).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/io/exr_io.h"
#include "common/job/job_types.h"

namespace mlt {

// A bootstrap whose b has a larger relative standard error than this gets a warning (the whole image
// carries b's error as a brightness error that no number of mutations removes).
constexpr double kMaxRelativeStdErrB = 0.02;

struct ChainLengthReport {
  int k = 0;
  double bk = 0, bkStdErr = 0;
  uint64_t chains = 0, mutations = 0;
  double acceptance = 0;  // accepted / proposed of chains of this length
  std::vector<std::pair<uint64_t, double>> kinds;  // per mutation kind (ChainReport::kinds order): proposed, acceptance
};

struct MutationKindReport {
  std::string name;  // the method's name for it (RenderMethod::mutationKinds)
  uint64_t proposed = 0;
  double acceptance = 0;
  double seconds = 0;  // wall time of its steps summed over chains (0: not measured, e.g. a farm image)
  double mutationsPerSecond() const { return seconds > 0 ? double(proposed) / seconds : 0.0; }
};

struct ChainReport {
  std::string method;
  double b = 0, bStdErr = 0;                  // as developed: bootstrap + large steps (develop.h (D3))
  double bBootstrap = 0, bBootstrapStdErr = 0;  // the bootstrap's alone (it allocated the chains)
  double directShare = -1, directCv = -1;       // the direct-light pilot's (Normalization); -1: none ran
  uint64_t bootstrapSamples = 0;              // bootstrap candidates (all lengths)
  uint64_t bootstrapSamplesInB = 0;           // of those, the ones b is developed from (Normalization)
  uint64_t bSamples = 0;                      // samples b was pooled from (those candidates + large steps)
  // mmlt, rjmlt with --b-sample-every N: the lengths of several techniques refine b_k by the chains' b samples
  // (develop.h (D9)), one per N mutations, instead of by their large steps; 0: by the large steps.
  uint64_t bSampleEvery = 0;
  uint64_t chains = 0, mutations = 0;
  // The plan's most crowded start (crowdedStart): `chains` of the `of` chains of path length k (-1: the one
  // length of pssmlt) start from bootstrap candidate `candidate`; chains == 0: none crowded.
  struct CrowdedStart {
    int k = -1;
    uint64_t chains = 0, of = 0, candidate = 0;
  } crowdedStart;
  double mutationsPerPixel = 0;
  bool hasAcceptance = false;  // false: an image whose metadata does not carry the acceptance keys
  double acceptance = 0;
  std::vector<MutationKindReport> kinds;   // the method's mutation kinds, index = Proposal::kind
  uint64_t steps(const std::string& kind) const;        // proposals of that kind (0 if unknown)
  double acceptanceOf(const std::string& kind) const;   // its acceptance (0 if unknown)
  std::vector<ChainLengthReport> lengths;  // mmlt only, ascending k
  RenderSettings settings;                 // the chain settings recorded with the report (not all of them)
  double relativeStdErr() const { return b > 0 ? bStdErr / b : 0.0; }
};

// Chains start from bootstrap candidates drawn in proportion to c (stratified over the alias table), so a
// candidate holding a share q of its length's c starts about q x C of its C chains. Where the bootstrap met a
// rare path far above its true share (caustic-mirror, seed 9 at 256x256 and 16 s: 34 of the 57 chains of
// length 6 on one candidate), those chains sit on it for much of their mutations and its pixel comes out many
// times too bright (relMSE 184 against a median of 0.08; docs/CHAINS.md, "Crowded starts": of 12 seeds there
// it names the 3 whose error stood out, no other). Unbiased over seeds, but the run is ruined, and the plan
// shows it before any chain runs: the report names it, the warnings say so. Crowded: at least
// kCrowdedStartChains chains on one candidate and at least kCrowdedStartShare of the length's chains (measured
// there: the bad runs had 22-60% on one candidate, the good ones at most 19%; at 256x256 and 4 s mmlt on door-ajar
// and textured-serialized had 17% and 13%).
constexpr uint64_t kCrowdedStartChains = 4;
constexpr double kCrowdedStartShare = 0.2;
ChainReport::CrowdedStart crowdedStart(const JobPlan& plan);
// "N of the M chains of path length k start from one bootstrap candidate (I): ..." with the remedy, one
// sentence without a newline; "" where chains == 0. The render's warning and the planners' log lines.
std::string describeCrowdedStart(const ChainReport::CrowdedStart& crowded);

// From a plan and the chains merged so far (units of the direct pass of separateDirect are not chains).
ChainReport makeChainReport(const JobPlan& plan, const PartialResult& merged);
void addChainMetadata(const ChainReport& report, ImageMetadata& metadata);
// NAMESeconds of every kind with seconds > 0 (wall-clock keys: not for the farm's images).
void addMoveSecondsMetadata(const ChainReport& report, ImageMetadata& metadata);
// The inverse of addChainMetadata (keys that are missing stay 0; hasAcceptance tells if acceptance was there).
ChainReport chainReportFromMetadata(const ImageMetadata& metadata);

// The summary printed after a render, several lines, each ending in '\n':
//   b = X ± SE (rel. R%, N bootstrap samples, T s)
//   a table per path length (mmlt), acceptance, mutations / seconds / mutations per second, and the
//   mutations per second of each move on one thread when the report has their seconds.
// bootstrapSeconds < 0 leaves the time out of the first line; chainSeconds is the wall time of the chains
// (secondsNote, e.g. " (wall time incl. startup)", follows it when it is something else).
std::string formatChainSummary(const ChainReport& report, double bootstrapSeconds, double chainSeconds,
                               const std::string& secondsNote = "");
// "large 2000 (1000 in 0.5 s), small ..." for the kinds with seconds > 0: their mutations per second on one
// thread; "" if the report has no seconds.
std::string formatMoveRates(const ChainReport& report);
// "warning: ... increase --bootstrap\n" when b's relative standard error exceeds kMaxRelativeStdErrB, else "".
std::string chainWarnings(const ChainReport& report);

}  // namespace mlt
