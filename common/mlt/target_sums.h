// b refined as the job runs (derivation (D3)-(D5) in common/mlt/develop.h): per path length slot, the
// bootstrap's estimate (Normalization::bootstrapB: mean, standard error from its randomization groups,
// and c's variance per uniform sample) is combined with the sums of c over the chains' large steps
// (ChainStats::largeStepSums, merged by addition).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mlt {

struct TargetSums {
  uint64_t n = 0;           // samples
  double sum = 0;           // S = sum of c
  double sumSq = 0;         // Q = sum of c^2
  void add(double c) {
    ++n;
    sum += c;
    sumSq += c * c;
  }
  void add(const TargetSums& o) {
    n += o.n;
    sum += o.sum;
    sumSq += o.sumSq;
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
// each large step is).
struct BootstrapEstimate {
  uint64_t n = 0;
  double b = 0, stdErr = 0, sampleVar = 0;
  bool operator==(const BootstrapEstimate&) const = default;
};

// (D5): the bootstrap's b and the large steps' mean, weighted by inverse variance. The large steps' variance
// in the weights is the model sampleVar / n_L, computed from the bootstrap, never from the large steps
// themselves: weights that depend on the values they weight would bias a heavy-tailed c low.
// The standard error reported is Var(w0 b0 + (1 - w0) bL) = w0^2 v0 + (1 - w0)^2 Var(bL), with Var(bL) the
// larger of the model and the large steps' own spread S2 / n_L: a heavy tail the bootstrap never saw (its
// model, hence the weights, too small) shows in the large steps that did see it, and the error then says
// so (caustic-mirror: rare s = 0 paths through the mirror, docs/CHAINS.md). With the model the larger,
// this is the inverse-variance formula sqrt(v0 vL / (v0 + vL)).
inline BEstimate combineB(const BootstrapEstimate& boot, const TargetSums& large) {
  if (large.n == 0) return {boot.b, boot.stdErr, boot.n};
  const double bL = large.sum / double(large.n);
  if (boot.n == 0) return pooledB({}, large);
  const double v0 = boot.stdErr * boot.stdErr, vL = boot.sampleVar / double(large.n);
  const uint64_t n = boot.n + large.n;
  const double nL = double(large.n);
  const double spread = large.n > 1 ? std::max(0.0, (large.sumSq - nL * bL * bL) / (nL - 1)) / nL : 0.0;
  if (!(v0 + vL > 0)) {
    const double wL = nL / double(n);  // both exact by the model: by count
    return {(1 - wL) * boot.b + wL * bL, wL * std::sqrt(spread), n};
  }
  const double w0 = vL / (v0 + vL);  // the bootstrap's weight
  const double varL = std::max(vL, spread);
  return {w0 * boot.b + (1 - w0) * bL, std::sqrt(w0 * w0 * v0 + (1 - w0) * (1 - w0) * varL), n};
}

// Element-wise sum of per-slot sums (the shorter side counts as zero).
inline void addPerSlot(std::vector<TargetSums>& a, const std::vector<TargetSums>& b) {
  if (a.size() < b.size()) a.resize(b.size());
  for (size_t i = 0; i < b.size(); ++i) a[i].add(b[i]);
}

}  // namespace mlt
