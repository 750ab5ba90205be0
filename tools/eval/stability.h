// Stability analysis over a set of runs: which runs are outliers, which methods are biased or get stuck.
//
// A group is (scene, method, budget): R independent runs of the same settings.
//  - outlier ("firefly") run: relMSE > outlierRatio x the group median, or, with >= 5 runs, a robust
//    z-score of log relMSE (median / 1.4826 MAD) above robustZ while at least minRatio x the median.
//  - brightness run ("missing transport" in one run): its mean-brightness error lies outside the
//    prediction interval of the other runs of its group, t = (m_i - mean_others) / (s_others sqrt(1 + 1/(n-1)))
//    with n - 2 degrees of freedom, p < runAlpha, and |m_i - mean_others| >= minBias.
//  - stuck run: a path length with >= stuckMinProposals proposals accepts less than stuckAcceptance of
//    them, or a chain of the run (in-process runs record per-chain statistics) does.
//  - concentrated run: its kTopPixels worst pixels hold at least concentratedShare of its relMSE
//    (metrics.h, topShare), on an image of at least concentratedMinPixels (on a smaller one 4 pixels are
//    a sizeable part of the image): a Markov chain confined to a few pixels (its whole share of the image
//    lands there), or one firefly. A run can be flagged so without being an outlier of its group (all
//    runs of a method may do it), and such an image is unusable however low its mean error.
// Method verdicts per (scene, method):
//  - biased ("missing or extra transport"): in each budget group the mean of the runs' relative
//    brightness errors is tested against 0 with t = mean / sqrt(s^2 / n + sigma_ref^2) (n - 1 dof;
//    sigma_ref = the reference's own relative standard error, so reference noise never looks like bias).
//    The groups' p-values are combined with Fisher's method, Bonferroni-corrected over all
//    (scene, method) pairs, and the method is flagged if p < biasAlpha and the estimated bias is at
//    least minBias (a relevance floor).
//  - unstable: at least one outlier run; stuck: at least one stuck run; concentrated: at least one
//    concentrated run.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "tools/eval/run_record.h"

namespace mlt::eval {

struct StabilityConfig {
  double outlierRatio = 4.0;
  double minRatio = 1.5;
  double robustZ = 5.0;
  double runAlpha = 1e-3;
  double biasAlpha = 1e-3;
  double minBias = 0.01;             // 1% of the mean brightness
  double stuckAcceptance = 1e-3;
  double stuckMinProposals = 1000;
  double concentratedShare = 0.3;
  uint64_t concentratedMinPixels = 64 * 64;
};

struct MethodVerdict {
  std::string scene, method;
  int runs = 0;
  bool biased = false;
  double bias = 0, biasStdErr = 0, biasP = 1;  // inverse-variance pooled relative brightness error
  int outlierRuns = 0, brightnessRuns = 0, stuckRuns = 0, nonFiniteRuns = 0, concentratedRuns = 0;
  double worstTopShare = 0;                    // max topShare over concentrated runs
  double worstOutlierRatio = 0;                // max relMSE / group median over outlier runs
  std::vector<std::string> problems;           // human-readable, one per failure mode
  bool ok() const { return problems.empty(); }
};

struct StabilityReport {
  std::vector<MethodVerdict> verdicts;         // sorted by scene, then method order of first appearance
};

// Fills RunRecord::flags (each flag "kind:detail") and returns the per-method verdicts.
// refNoise: per scene (missing = a reference of unknown noise, treated as noise-free).
StabilityReport analyzeStability(std::vector<RunRecord>& runs, const std::map<std::string, ReferenceNoise>& refNoise,
                                 const StabilityConfig& config = {});

}  // namespace mlt::eval
