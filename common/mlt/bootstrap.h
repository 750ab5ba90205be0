// The bootstrap phase (run by the coordinator): N candidate paths, each a pure function of (job seed,
// candidate index), whose target values c give the normalization b = E[c] (and b_k per path length for
// mmlt) with its standard error, and an alias table from which chains draw their start states in
// proportion to c.
//
// Candidate indexing: path length slot l (l = 0 for pssmlt; l = k - kMin for mmlt; firstSlot + i for
// the i-th length of a config) owns candidates
// [l << kCandidateSlotBits, (l + 1) << kCandidateSlotBits); its first n candidates are evaluated.
// Candidate i reads IndependentSource(jobSeed, i). A worker replays candidate i with exactly that source.
//
// Sizing (architecture notes: a small bootstrap misestimates b, and an error in b is an error in the
// image's brightness that no number of mutations removes): every length starts with candidatesPerLength
// candidates; while b = sum b_k has a relative standard error sqrt(sum se_k^2) / b above targetRelStdErr,
// the length with the largest variance se_k^2 doubles its count; sizing stops when that length reaches
// maxGrowth x candidatesPerLength.
// The decisions depend only on the candidates' values, so the result is still a pure function of (seed,
// settings). They also bias b_k low where c has a heavy tail (optional stopping: a length that missed its
// rare bright paths looks certain and stops small, one that caught them grows and dilutes them; on
// cornell-spheres' mmlt the bootstrap's b was 3.7% low on average over 401 runs, the image 0.14%), and by the
// same dilution they damp that tail: b_k from fresh candidates of a count fixed in advance was unbiased but
// left 5 of 56 paired mmlt and rjmlt runs on caustic-mirror at over 6x the median error (this rule: none),
// ruined by a single giant candidate (docs/CHAINS.md, "mmlt's brightness on cornell-spheres"), so this rule
// stays for what the estimate decides: the chains' allocation, starts and Kelemen weights. The image's b
// is developed from the first round alone (LengthBootstrap::fixedEstimate), whose count no value decided:
// unbiased, and the large steps outnumber it anyway (develop.h (D3)).
//
// Determinism: candidates are evaluated in parallel (TBB) into an array; every reduction (b, variance,
// alias table) then runs sequentially in index order, so the result is bit-identical for any thread count.
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <vector>

#include "common/mlt/alias_table.h"
#include "common/mlt/target_sums.h"
#include "common/sampler/sample_source.h"  // kCandidateSlotBits, kCandidateGroups

namespace mlt {

// c(x) of candidate `index` for path length `pathLength` (-1: any length). Must be a pure function.
using CandidateFn = std::function<double(uint64_t index, int pathLength)>;
// Makes a CandidateFn with its own scratch buffers (called once per parallel task).
using CandidateFnFactory = std::function<CandidateFn()>;
// The same, also reporting the film bin the candidate's light lands in (kNoBin: none), which the chain
// allocation uses to weigh path lengths by where their light lands (allocation.h, allocationWeights), and
// its work: the primary-sample numbers it drew (IndependentSource::reads), a deterministic measure of its
// cost (a vertex draws a few numbers and traces a ray), which the budgeted sizing counts.
constexpr uint32_t kNoBin = UINT32_MAX;
// luminance (BootstrapConfig::luminance): the luminance of the candidate's path, which a relative target's c is not
// (importance.h): its mean estimates b_lum, the image's brightness, which the development keeps (develop.h
// (D8)).
struct CandidateInfo {
  uint32_t bin = kNoBin;
  uint32_t work = 0;
  double luminance = -1;
};
using BinnedCandidateFn = std::function<double(uint64_t index, int pathLength, CandidateInfo* info)>;
using BinnedCandidateFnFactory = std::function<BinnedCandidateFn()>;


struct BootstrapConfig {
  uint64_t candidatesPerLength = 100000;  // initial count per path length
  double targetRelStdErr = 0;             // 0: a fixed size
  uint64_t maxGrowth = 1;                 // at most maxGrowth x candidatesPerLength per length
  // > 0: a budget instead of a target: the cost of totalCandidates of the chains' mutations (chainMixCost).
  // After the first round, the length whose doubling removes most of b's variance per unit of cost
  // (largest se_k^2 / (n_k cost_k), cost_k = candidateCost) doubles, while the total cost stays within the
  // budget. Also with one length: it doubles while it fits.
  uint64_t totalCandidates = 0;
  std::vector<int> pathLengths = {-1};  // pssmlt: {-1}; mmlt: {kMin, ..., kMax}
  uint64_t firstSlot = 0;                // slot of pathLengths[0] (a later block of lengths continues the slots)
  bool parallel = true;
  // Lengths whose b the caller estimates otherwise (mmlt's length 1 by camera rays, common/job/
  // emission_estimate.h): their candidates only seed chains, so the budget (or the target) never grows
  // them; they keep the first round's count.
  std::vector<int> seedOnlyLengths;
  // Keep each candidate's CandidateInfo::luminance and summarize it (LengthBootstrap::luminanceEstimate): a
  // relative target's b_lum (develop.h (D8)). Binned bootstraps only.
  bool luminance = false;
  // Cost the caller already spent from the budget (in the candidates' unit, numbers drawn; mmlt: b_1's
  // camera rays, kEmissionRayCost each), so that the whole bootstrap, not only its candidates, fits it.
  double spentCost = 0;
};

// The candidates above the tail threshold: about 1 in 1024, at least kCandidateGroups (develop.h (D3)).
inline uint64_t tailCandidates(uint64_t N) { return std::max<uint64_t>(kCandidateGroups, N / 1024); }

// b's estimate from the candidates of one length (target_sums.h): mean, standard error from the
// kCandidateGroups randomization groups (i.i.d. if N is not a multiple of them), sample variance, and the
// tail split at tau (develop.h (D3)).
BootstrapEstimate summarizeCandidates(const std::vector<double>& c);
BootstrapEstimate summarizeCandidates(const double* c, uint64_t n);  // the first n of an array (a prefix)

struct LengthBootstrap {
  int pathLength = -1;
  uint64_t firstCandidate = 0;
  std::vector<double> c;  // target value of each candidate
  std::vector<uint32_t> bin;  // film bin of each candidate (runBinnedBootstrap only; else empty)
  std::vector<uint32_t> work;  // numbers drawn by each candidate (runBinnedBootstrap only; else empty)
  std::vector<double> luminance;  // each candidate's luminance (BootstrapConfig::luminance), else empty
  // b (the mean), stdErr (from the kCandidateGroups group means), sampleVar (c's variance per candidate,
  // i.i.d. formula: a uniform sample's variance) and the tail split of develop.h (D3): what the plan keeps.
  BootstrapEstimate estimate;
  BootstrapEstimate luminanceEstimate;  // the same summary of `luminance` (n = 0: not kept)
  // The same two summaries of the first fixedCount candidates only: those whose count no candidate's value
  // decided (the first round of a sizing that grows lengths by their values; every candidate where only
  // the cost grows them, as with one length). Their mean is unbiased, which `estimate`'s is not where the
  // sizing grew lengths by their values (see Sizing above): the image's b is developed from these
  // (develop.h (D3)), while `estimate` (more candidates, its heavy tail damped) allocates the chains and
  // weights Kelemen MIS, where a bias costs efficiency, not brightness.
  uint64_t fixedCount = 0;
  BootstrapEstimate fixedEstimate, fixedLuminanceEstimate;
  AliasTable table;       // over c; empty if b == 0
};

struct BootstrapResult {
  std::vector<LengthBootstrap> lengths;
  double b = 0, bStdErr = 0;  // sum over lengths
  uint64_t candidates = 0;
  double seconds = 0;
};

// The cost of one candidate of a length, in numbers drawn: kCandidateOverhead (the per-candidate work
// that draws nothing) + the length's mean numbers drawn. Fitted with tests/bench/bootstrap_cost_bench
// (mmlt, depth 12, 256x256): a candidate of length 12 takes 13x the time of one of length 1 on
// caustic-mirror and draws 9x the numbers; 3.9x and 5.2x on the Cornell box (Russian roulette ends most
// long paths early); a fit of time against numbers drawn leaves no overhead to speak of (docs/CHAINS.md).
constexpr double kCandidateOverhead = 1;
double candidateCost(const LengthBootstrap& lb);
// What a bootstrap's candidates cost in all: sum over lengths of n_k candidateCost_k.
double bootstrapCost(const std::vector<LengthBootstrap>& lengths);
// The cost of what the chains of a length do: a chain's states are distributed as c, so its small steps
// cost the c-weighted mean of the candidates' cost (bright paths can be short: the light seen directly),
// its large steps a candidate's; kCostLargeStepShare of each (the default large-step probability: the
// bootstrap does not depend on the chains' settings, so a plan may use another).
constexpr double kCostLargeStepShare = 0.3;
double chainCost(const LengthBootstrap& lb);
// The mean cost of a mutation of the chains' mix of lengths: chainCost of each length in proportion to
// the mutations the plan gives it (allocation.h, mutationWeights: b_k sqrt(gbar_k) where the candidates
// are binned, else b_k). The budget of a budgeted bootstrap is totalCandidates x this, measured on its
// first round. (Weighted by b_k alone it priced a mutation by lengths the chains hardly run: on
// caustic-mirror a heavy-tailed b_9 made it 1.5x the mix's real cost, and the bootstrap 6.4% of a job
// planned at 4%: docs/CHAINS.md.)
double chainMixCost(const std::vector<LengthBootstrap>& lengths);

BootstrapResult runBootstrap(const BootstrapConfig& config, const CandidateFnFactory& makeCandidateFn);
// The same, keeping every candidate's film bin in LengthBootstrap::bin and the lengths' work (identical c
// and b; the budgeted sizing counts the work, so its doublings may differ).
BootstrapResult runBinnedBootstrap(const BootstrapConfig& config, const BinnedCandidateFnFactory& makeCandidateFn);

// Largest-remainder (Hamilton) apportionment of `total` among weights (ties to the lower index):
// deterministic, sums exactly to total, and each share is within 1 of total * w_i / sum(w).
std::vector<uint64_t> apportion(uint64_t total, const std::vector<double>& weights);

}  // namespace mlt
