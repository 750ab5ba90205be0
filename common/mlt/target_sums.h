// Sums of the target function c over independent uniform samples of one path length, and the pooled
// estimate of b_k they give: b refined as the job runs. Derivation (D3, D4) in common/mlt/develop.h.
// A job keeps one TargetSums per path length slot for its bootstrap (Normalization::bootstrapSums) and
// one per slot for the large steps of its chains (ChainStats::largeStepSums); both merge by addition.
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

// (D3, D4): the pooled mean of bootstrap and large-step samples and its standard error.
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

// Element-wise sum of per-slot sums (the shorter side counts as zero).
inline void addPerSlot(std::vector<TargetSums>& a, const std::vector<TargetSums>& b) {
  if (a.size() < b.size()) a.resize(b.size());
  for (size_t i = 0; i < b.size(); ++i) a[i].add(b[i]);
}

}  // namespace mlt
