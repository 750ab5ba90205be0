// The chain loop, written once for every Markov chain method:
//   propose -> evaluate -> a = min(1, T-ratio * c(y) / c(x)) -> accept/reject -> weighted splats to a sink.
//
// The three roles are interfaces so that the same loop serves
//   - primary-sample-space chains (pssmlt, pssmlt-bdpt, mmlt): a KelemenSource behind ChainState, a path
//     evaluator or an mmlt technique evaluator behind ChainTarget (pss_chain.h);
//   - reversible-jump MLT (later): a writable sample source whose jumps report T-ratio * |Jacobian|;
//   - Veach's path-space MLT (later): a path state whose mutations report their own T-ratio.
// Nothing here assumes a primary sample space.
//
// Splatting (the estimator of pixel j is  b * P / M_total * sum of weighted splats, see develop.h):
//   ExpectedValue (Veach 1997): per step the proposal y gets weight a / c(y) and the current state x
//     weight (1 - a) / c(x); each step distributes total weight 1 over {x, y} in units of f / c.
//   KelemenMIS (Kelemen et al. 2002, sec. 5-6): the Metropolis samples (density c/b per mutation,
//     M of them) are combined with the large-step samples (uniform density 1, expected p_large * M of
//     them) by the balance heuristic. The paper's weights, in image units, are
//        proposal: (a + L) / ((c(y)/b + p_large) M),    current: (1 - a) / ((c(x)/b + p_large) M),
//     with L = 1 for a large step. To keep one development scale b * P / M for both schemes we factor
//     b / M out:  (a + L) / ((c(y)/b + p_large) M) = (b / M) * (a + L) / (c(y) + b p_large),
//     so the chain splats with weight (a + L) / (c(y) + b p_large) and (1 - a) / (c(x) + b p_large).
//     With p_large = 0 these reduce to the expected-value weights a / c(y), (1 - a) / c(x).
//     Hence a chain using KelemenMIS must be given b (its own b_k for an mmlt chain of length k).
//     That b is the bootstrap's, b_w, while the image is developed with the refined b^ (develop.h (D3)).
//     In expectation the Metropolis share of pixel j's sum is (M / b) * integral of c f_j / (c + b_w p),
//     the large steps' share p M * integral of f_j / (c + b_w p) (uniform samples: no b in it). Developed
//     together with b^ P / M, pixel j would be  integral of f_j (b^ p + (b^/b) c) / (c + b_w p), off by
//     p (b - b_w) / (c + b_w p) of f_j where b_w misses b: up to b_w's whole error in dark pixels. So the
//     large steps' share goes to a layer of its own (ChainSink::largeStepSplat), developed with b_w P / M:
//     b_w p + (b^/b) c over c + b_w p, which is 1 when b^ = b, whatever b_w is.              (chain.h (K1))
// Weights of the current state are accumulated and splatted once when the state changes (Kelemen's
// Next(), sec. 6): fewer splats, same estimator.
#pragma once
#include <cstdint>
#include <limits>

#include "common/core/rng.h"
#include "common/core/vec.h"
#include "common/integrators/path_evaluator.h"
#include "common/mlt/importance.h"
#include "common/mlt/kelemen_source.h"
#include "common/mlt/target.h"
#include "common/mlt/target_sums.h"

namespace mlt {

enum class ChainSplatting { ExpectedValue, KelemenMIS };

// A proposal's kind is an index into its method's mutation kind names (RenderMethod::mutationKinds:
// pssmlt's "large", "small"; later methods name their own), so statistics are kept per kind without a
// shared enum.
constexpr int kMaxMutationKinds = 8;
struct Proposal {
  int kind = 0;              // in [0, kMaxMutationKinds)
  double tRatio = 1;         // T(y -> x) / T(x -> y) (times |Jacobian| for reversible jumps); 1 for PSS steps
  bool independent = false;  // drawn from the uniform density, independently of the state (a large step):
                             // its c(y) is a sample of b (develop.h (D3)) and Kelemen MIS counts it
};

// The chain's state. propose() turns the current state into a proposal in place (remembering how to undo
// it); accept() commits it, reject() restores the previous state exactly.
class ChainState {
 public:
  virtual ~ChainState() = default;
  virtual Proposal propose() = 0;
  virtual void accept() = 0;
  virtual void reject() = 0;
  // The stratum point of an independent proposal, called after it was evaluated: two of its uniform
  // coordinates in [0,1)^2 (a primary-sample chain: the camera's film position, Camera[0,1]), by which its
  // c is post-stratified (develop.h (D6)). Negative: the state has none (b's sums are then pooled only).
  virtual Vec2 stratumPoint() { return {-1.f, -1.f}; }
};

// Evaluates the state's current point (the proposal, after propose()) into a path contribution.
class ChainTarget {
 public:
  virtual ~ChainTarget() = default;
  virtual void evaluate(PathContribution& out) = 0;
};

// Receives weighted splats: every splat of `path` times `weight` (see the scheme above).
class ChainSink {
 public:
  virtual ~ChainSink() = default;
  virtual void splat(const PathContribution& path, double weight) = 0;
  // Kelemen MIS: a large step's own share (the L of the weights above), developed with the chain's b_w
  // (K1). A sink without a layer for it adds it to the others (right only where b_w is b).
  virtual void largeStepSplat(const PathContribution& path, double weight) { splat(path, weight); }
  // An independent proposal's bulk m = min(c, tau) at its stratum point u in [0,1)^2 (ChainState::
  // stratumPoint; develop.h (D6)). A sink that keeps no strata ignores it.
  virtual void stratumSample(Vec2 u, double m) { (void)u, (void)m; }
};

struct ChainConfig {
  ChainSplatting splatting = ChainSplatting::ExpectedValue;
  double largeStepProb = 0;  // p_large, for KelemenMIS weights
  double b = 0;              // normalization (KelemenMIS only; must be > 0 there)
  // The bootstrap's tail threshold for the large steps' sums (develop.h (D3)); infinity: no split.
  double tau = std::numeric_limits<double>::infinity();
  // Post-stratify the large steps (develop.h (D6)): pass each one's bulk and ChainState::stratumPoint to
  // ChainSink::stratumSample.
  bool stratifyLargeSteps = false;
  // The target's importance map (importance.h (R2)) and power (target.h (T1)); none and 1: c is the path's
  // luminance. The start state's c (runChain's cx) must have been computed with the same shape.
  TargetShape target;
  // With a shaped target: the tail threshold of the large steps' luminance sums (ChainCounts::largeStepsLuminance).
  double luminanceTau = std::numeric_limits<double>::infinity();
  // a = min(1, (T-ratio * c(y)/c(x))^acceptancePower). 1 for every correct chain; the 1D tests set 0.5
  // (a deliberately wrong chain, sampling c^(1/2)) to show that they can fail.
  double acceptancePower = 1;
};

// Wall time per move kind (issue 12, "mutations per second reported per move"): every
// kMoveTimingStride-th step is timed with steady_clock, from before propose() to after the accept/reject
// and its splat; a kind's seconds are its timed steps' mean time its proposals. (Timing every step would
// cost two clock reads, ~60 ns, per step of ~1.5 us: 4 %; one step in 16: 0.25 %.) A kind proposed but
// never timed gets the mean of all timed steps (step 0 is always timed), so seconds > 0 wherever
// proposed > 0. Never read by the chain: images and counts do not depend on it.
constexpr uint64_t kMoveTimingStride = 16;

struct ChainCounts {
  uint64_t proposed[kMaxMutationKinds] = {}, accepted[kMaxMutationKinds] = {};  // index = Proposal::kind
  double seconds[kMaxMutationKinds] = {};  // estimated wall time of each kind's steps (see above)
  // c(y) of every independent proposal (a large step), accepted or not: uniform samples of the target,
  // which refine b as the job runs (develop.h (D3)).
  TargetSums largeSteps;
  // With a shaped target (ChainConfig::target): the luminance of those proposals (b_lum, develop.h (D8)).
  TargetSums largeStepsLuminance;
};

// Runs `mutations` steps from the current state x (already evaluated into `current`, target value cx > 0,
// the state's start accepted). Buffers `current` and `scratch` are reused (no allocation once warm);
// on return `current` holds the final state. acceptRng decides acceptance.
ChainCounts runChain(ChainState& state, ChainTarget& target, const ChainConfig& config, ChainSink& sink,
                     Pcg32& acceptRng, uint64_t mutations, PathContribution& current, double cx,
                     PathContribution& scratch);

}  // namespace mlt
