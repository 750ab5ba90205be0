// The types of a render job as the farm sees it, independent of the method: settings -> plan (bootstrap,
// work units) -> partial results of work units -> one developed image. The functions that make and use
// them are the method's (common/methods/method.h); the job API over the registry is
// common/methods/registry.h:
//
//   JobPlan plan = planJob(scene, settings);            // coordinator: bootstrap for MLT methods
//   PartialResult r = runWorkUnit(scene, plan, unit);   // worker: a chain, or a batch of pixel samples
//   merged.add(r) for units in index order;              // coordinator or `mltfarm merge`
//   std::vector<Color> img = developImage(plan, merged); // normalization applied once, here
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "common/film/film.h"
#include "common/film/sparse_splats.h"
#include "common/integrators/path_evaluator.h"
#include "common/mlt/importance.h"
#include "common/mlt/target.h"
#include "common/mlt/target_sums.h"
#include "common/settings/render_settings.h"

namespace mlt {

// One independent piece of work: a Markov chain or a batch of pixel samples. Small and serializable.
struct WorkUnit {
  uint32_t index = 0;            // chain index / batch index; results are merged in this order
  // Sample batch: samples [sampleBegin, sampleEnd) of every pixel (lt: light paths in that range).
  uint32_t sampleBegin = 0, sampleEnd = 0;
  // Markov chain.
  uint64_t startCandidate = 0;   // bootstrap candidate index the chain starts from
  int pathLength = -1;           // mmlt: path length k (segments); -1 otherwise
  uint64_t mutations = 0;
  double startContribution = 0;  // c(x0) recorded by the bootstrap; the worker's replay must reproduce it
};

// Normalization inputs decided by the plan, needed both by chains and by development.
struct Normalization {
  // The bootstrap's estimates: they allocate chains to lengths and weight Kelemen MIS splats. The image
  // is developed with b pooled from these sums and the chains' large steps (mlt/develop.h (D3)).
  double b = 0, bStdErr = 0;                 // mean target value c over the bootstrap (all lengths)
  std::vector<double> bk, bkStdErr;          // mmlt: per path length k (index = k)
  std::vector<BootstrapEstimate> bootstrapB; // per path length slot (pssmlt: 0; mmlt: k)
  std::vector<uint64_t> mutationsPerLength;  // mmlt: total planned mutations per length
  uint64_t totalMutations = 0;
  uint64_t bootstrapSamples = 0;
  // Of those, the candidates whose values the image's b is developed from (bootstrapB; bootstrap.h,
  // LengthBootstrap::fixedCount): a multi-length sizing's first round. The rest only seed and allocate.
  uint64_t bootstrapSamplesInB = 0;
  double bootstrapSeconds = 0;
  // The direct-light pilot of a job whose settings left the choice to the plan (DirectLight::Auto,
  // common/job/direct_light_rule.h): its share and CV; -1 where no pilot ran (the CV also where the share
  // alone decided).
  double directShare = -1, directCv = -1;
  // The relative target's importance map (common/mlt/importance.h (R2)), which every chain's target reads;
  // empty: the target is the path's luminance.
  ImportanceMap importance;
  // The tempered target's power beta (common/mlt/target.h (T1)); 1: c is linear in the path's light.
  double targetPower = 1;
  // The chains' target shape: the map above (if any) and the power.
  TargetShape target() const { return TargetShape{importance.empty() ? nullptr : &importance, targetPower}; }
  // With a shaped target (a map, or a power other than 1): the bootstrap's estimate of b_lum per slot, the
  // mean luminance of a uniform sample (its candidates' luminance; b_1's camera rays unweighted), to which
  // the development scales each slot's image (mlt/develop.h (D8)). Empty otherwise.
  std::vector<BootstrapEstimate> bootstrapLuminance;
  double luminanceTailThreshold(size_t slot) const {
    return slot < bootstrapLuminance.size() ? bootstrapLuminance[slot].tau : std::numeric_limits<double>::infinity();
  }
  // The b a chain of `slot` weights Kelemen MIS splats with, and its large-step layer is developed with
  // (mlt/develop.h (D7)): the bootstrap's b_k (mmlt, rjmlt) or b.
  double weightB(size_t slot) const { return bk.empty() ? b : (slot < bk.size() ? bk[slot] : 0.0); }
  // The tail threshold the chains of a slot split their large steps' sums at (develop.h (D3)); infinity
  // where the plan has no bootstrap for the slot.
  double tailThreshold(size_t slot) const {
    return slot < bootstrapB.size() ? bootstrapB[slot].tau : std::numeric_limits<double>::infinity();
  }
};

struct JobPlan {
  RenderSettings settings;       // with width/height/chains/samplesPerUnit resolved
  Normalization norm;
  std::vector<WorkUnit> units;
};

struct ChainStats {              // sums, so they merge by addition
  std::vector<uint64_t> proposedPerLength, acceptedPerLength;  // index = path length (pssmlt: index 0)
  std::vector<uint64_t> proposedPerKind, acceptedPerKind;  // index = mutation kind (the method's mutationKinds())
  // Per path-length slot and kind: index = slot * kKindStride + kind (rjmlt's technique changes per length).
  static constexpr size_t kKindStride = 8;  // = kMaxMutationKinds (common/mlt/chain.h)
  std::vector<uint64_t> proposedPerLengthKind, acceptedPerLengthKind;
  // Wall time spent in each kind's steps, summed over chains (chain.h kMoveTimingStride: an estimate from
  // sampled steps). Informational, like PartialResult::seconds: never part of the image.
  std::vector<double> secondsPerKind;
  std::vector<TargetSums> largeStepSums;     // c of every large step, per path length slot (quantized per unit)
  // With a relative target: every large step's luminance, per slot (b_lum, develop.h (D8)); else empty.
  std::vector<TargetSums> largeStepLuminanceSums;
  void add(const ChainStats& o);
};

struct PartialResult {
  Film film;                     // raw sums
  // A unit's splats not yet in `film` (a Markov chain's: a few thousand of the film's pixels, so that a
  // unit allocates and scans no dense film; common/film/sparse_splats.h). add() folds them in; a merged
  // result (a task's, a job's) holds everything in `film`.
  SparseSplats splats;
  uint64_t samples = 0;          // pixel samples (sample methods) or mutations (chains) it holds
  ChainStats stats;
  std::vector<uint32_t> units;   // work unit indices included (sorted)
  double seconds = 0;            // wall time spent (informational; never affects the image)
  // Element-wise sum. Callers add in unit-index order for bit-identical results.
  void add(const PartialResult& o);
  // `film` with the splats folded in (a unit's film as a dense film; a no-op on merged results).
  void foldSplats();
};

}  // namespace mlt
