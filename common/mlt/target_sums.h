// b refined as the job runs (derivation (D3)-(D5) in common/mlt/develop.h): per path length slot, the
// bootstrap's estimate (Normalization::bootstrapB: mean, standard error from its randomization groups,
// and c's variance per uniform sample) is combined with the sums of c over the chains' large steps
// (ChainStats::largeStepSums, merged by addition).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace mlt {

// Sums of c over i.i.d. uniform samples, split at the bootstrap's tail threshold tau (develop.h (D3)):
// the bulk min(c, tau) and the excess max(c - tau, 0) = c - min(c, tau). With tau = infinity (a plan
// without a threshold) the bulk is c.
struct TargetSums {
  uint64_t n = 0;           // samples
  double sum = 0;           // S = sum of c
  double sumSq = 0;         // Q = sum of c^2
  double bulk = 0;          // sum of min(c, tau)
  double bulkSq = 0;        // sum of min(c, tau)^2
  double excessSq = 0;      // sum of max(c - tau, 0)^2
  void add(double c, double tau = std::numeric_limits<double>::infinity()) {
    ++n;
    sum += c;
    sumSq += c * c;
    const double m = std::min(c, tau), e = c - m;
    bulk += m;
    bulkSq += m * m;
    excessSq += e * e;
  }
  void add(const TargetSums& o) {
    n += o.n;
    sum += o.sum;
    sumSq += o.sumSq;
    bulk += o.bulk;
    bulkSq += o.bulkSq;
    excessSq += o.excessSq;
  }
  bool operator==(const TargetSums&) const = default;
};

struct BEstimate {
  double b = 0, stdErr = 0;
  uint64_t samples = 0;
};

// The pooled mean and standard error of i.i.d. samples (two sets of them).
inline BEstimate pooledB(const TargetSums& bootstrap, const TargetSums& largeSteps) {
  TargetSums all = bootstrap;
  all.add(largeSteps);
  BEstimate e;
  e.samples = all.n;
  if (all.n == 0) return e;
  const double N = double(all.n);
  e.b = all.sum / N;                                                        // (D3)
  if (all.n > 1) e.stdErr = std::sqrt(std::max(0.0, (all.sumSq - N * e.b * e.b) / (N - 1)) / N);  // (D4)
  return e;
}

// The bootstrap's estimate of one length's b: mean of its candidates, the standard error of that mean
// (from the spread of its randomization groups' means: the candidates' film positions are spread evenly,
// which an i.i.d. formula would not see), and the variance of c for one uniform sample (which is what
// each large step is). The same for the bulk min(c, tau) below the tail threshold tau (the
// tailCandidates(n)-th largest candidate, bootstrap.h), and the mean of max(c - tau, 0)^2.
struct BootstrapEstimate {
  uint64_t n = 0;
  double b = 0, stdErr = 0, sampleVar = 0;
  double tau = std::numeric_limits<double>::infinity();
  double bulkB = 0, bulkStdErr = 0, bulkVar = 0, excessMeanSq = 0;
  bool operator==(const BootstrapEstimate&) const = default;
};

// The large steps' bulk post-stratified by film position (strata.h, postStratifiedMean; develop.h (D6)).
struct StratifiedMean {
  bool valid = false;  // at least 2 samples (else no variance: the caller pools)
  uint64_t n = 0;      // samples
  double mean = 0;     // m^ (D6)
  double var = 0;      // Var(m^) as estimated (D6)
  uint64_t strata = 0; // strata used
};

// (D3)-(D5): the bootstrap's bulk and the large steps' bulk weighted by inverse variance, the excess above
// tau pooled over every sample by count, and their sum. The weights see the bulk's statistics only.
// strata (optional, (D6)): the large steps' bulk post-stratified; it replaces their plain bulk mean, the
// two bulks are then weighted by count (the bootstrap's Halton positions and the strata remove the same
// between-pixel variance; a weight from the strata's own variance estimate, which moves with their mean
// where few samples share a stratum, biased b low by 16% on a small Cornell box), and the strata's
// estimated variance enters the stated standard error.
inline BEstimate combineB(const BootstrapEstimate& boot, const TargetSums& large,
                          const StratifiedMean* strata = nullptr) {
  if (large.n == 0) return {boot.b, boot.stdErr, boot.n};
  if (boot.n == 0 && !strata) return pooledB({}, large);
  const double n0 = double(boot.n), nL = double(large.n), n = n0 + nL;
  // The bulk: inverse variance, v_0 from the groups, v_L from the bootstrap's model (never from the large
  // steps' own values); both exact (zero variance), or post-stratified large steps: by count.
  const double v0 = boot.n > 0 ? boot.bulkStdErr * boot.bulkStdErr : 0.0;
  const double vL = strata ? strata->var : boot.bulkVar / nL;
  const double w0 = strata || !(v0 + vL > 0) ? n0 / n : vL / (v0 + vL);
  const double bulkL = strata ? strata->mean : large.bulk / nL;
  const double bulk = w0 * boot.bulkB + (1 - w0) * bulkL;
  // The large steps' stated variance: the strata's estimate, or the larger of the model and their own spread.
  const auto spreadL = [&] {
    return large.n > 1 ? std::max(0.0, (large.bulkSq - nL * bulkL * bulkL) / (nL - 1)) / nL : 0.0;
  };
  const double varBulk = w0 * w0 * v0 + (1 - w0) * (1 - w0) * (strata ? vL : std::max(vL, spreadL()));
  // The excess: the pooled mean of every sample's max(c - tau, 0), and its i.i.d. variance.
  // Without a threshold (tau = infinity: b_1 from camera rays) there is no excess: sum and bulk are the same
  // numbers, differing only by their independent rounding (quantizeSums), which must not make the
  // covariance below infinity * 0.
  const bool split = std::isfinite(boot.tau);
  const double excessSum = split ? n0 * (boot.b - boot.bulkB) + (large.sum - large.bulk) : 0.0;
  const double excess = std::max(0.0, excessSum / n);
  const double excessSq = n0 * boot.excessMeanSq + large.excessSq;
  const double varExcess = std::max(0.0, (excessSq - n * excess * excess) / (n - 1)) / n;
  // The two parts share samples. Per sample Cov(min(c, tau), max(c - tau, 0)) = E[e] (tau - E[m]) (e > 0
  // only where m = tau); both estimates weigh each sample's part with weights summing to 1 per set, so
  // Cov(bulk^, excess^) = Cov / n (treating the bootstrap's samples as i.i.d. here).
  const double cov = excess > 0 ? excess * (boot.tau - (n0 * boot.bulkB + large.bulk) / n) / n : 0.0;
  const double se = std::sqrt(std::max(0.0, varBulk + varExcess + 2 * cov));
  return {bulk + excess, se, boot.n + large.n};
}

// Element-wise sum of per-slot sums (the shorter side counts as zero).
inline void addPerSlot(std::vector<TargetSums>& a, const std::vector<TargetSums>& b) {
  if (a.size() < b.size()) a.resize(b.size());
  for (size_t i = 0; i < b.size(); ++i) a[i].add(b[i]);
}

}  // namespace mlt
