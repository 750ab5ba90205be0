#include "common/mlt/bootstrap.h"

#include "common/mlt/allocation.h"

#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace mlt {

BootstrapEstimate summarizeCandidates(const std::vector<double>& c) { return summarizeCandidates(c.data(), c.size()); }

BootstrapEstimate summarizeCandidates(const double* c, uint64_t N) {
  BootstrapEstimate e;
  e.n = N;
  if (N == 0) return e;
  double sum = 0;
  for (uint64_t i = 0; i < N; ++i) sum += c[i];
  e.b = sum / double(N);
  double sq = 0;
  for (uint64_t i = 0; i < N; ++i) sq += (c[i] - e.b) * (c[i] - e.b);
  e.sampleVar = N > 1 ? sq / double(N - 1) : 0.0;
  // Variance of the mean. Candidates spread their film positions evenly (sample_source.h), so the i.i.d.
  // formula overstates it; with whole randomization groups, their means are i.i.d. and give it exactly.
  const uint64_t G = kCandidateGroups;
  const bool grouped = N % G == 0 && N >= 2 * G;
  const auto groupVarOfMean = [&](auto value, double mean) {
    std::vector<double> groupSum(G, 0.0);
    for (uint64_t i = 0; i < N; ++i) groupSum[i % G] += value(c[i]);
    double gsq = 0;
    for (uint64_t g = 0; g < G; ++g) {
      const double d = groupSum[g] / double(N / G) - mean;
      gsq += d * d;
    }
    return gsq / (double(G) * double(G - 1));
  };
  e.stdErr = std::sqrt(grouped ? groupVarOfMean([](double x) { return x; }, e.b) : e.sampleVar / double(N));
  // The tail split (develop.h (D3)): tau = the tailCandidates(N)-th largest c.
  const uint64_t m = tailCandidates(N);
  if (N > 2 * m) {
    std::vector<double> sorted(c, c + N);
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(N - m), sorted.end());
    e.tau = sorted[N - m];
  }
  const double tau = e.tau;
  double bulkSum = 0, excessSq = 0;
  for (uint64_t i = 0; i < N; ++i) {
    const double x = std::min(c[i], tau);
    bulkSum += x;
    excessSq += (c[i] - x) * (c[i] - x);
  }
  e.bulkB = bulkSum / double(N);
  e.excessMeanSq = excessSq / double(N);
  double bsq = 0;
  for (uint64_t i = 0; i < N; ++i) bsq += (std::min(c[i], tau) - e.bulkB) * (std::min(c[i], tau) - e.bulkB);
  e.bulkVar = N > 1 ? bsq / double(N - 1) : 0.0;
  e.bulkStdErr = std::sqrt(grouped ? groupVarOfMean([tau](double x) { return std::min(x, tau); }, e.bulkB)
                                   : e.bulkVar / double(N));
  return e;
}

namespace {

BootstrapResult bootstrapImpl(const BootstrapConfig& config, const BinnedCandidateFnFactory& makeCandidateFn,
                              bool binned) {
  const auto start = std::chrono::steady_clock::now();
  if (config.candidatesPerLength < 2)
    throw std::invalid_argument("bootstrap: need at least 2 candidates per path length, got " +
                                std::to_string(config.candidatesPerLength));
  if (config.pathLengths.empty()) throw std::invalid_argument("bootstrap: no path lengths");
  if (config.maxGrowth < 1) throw std::invalid_argument("bootstrap: maxGrowth must be >= 1");
  const uint64_t N0 = config.candidatesPerLength;
  const uint64_t maxN = config.totalCandidates > 0 ? std::max(N0, config.totalCandidates) : N0 * config.maxGrowth;
  if (maxN >= (uint64_t(1) << kCandidateSlotBits))
    throw std::invalid_argument("bootstrap: too many candidates per path length: " + std::to_string(maxN));
  BootstrapResult result;
  std::vector<double> varMean(config.pathLengths.size(), 0.0);  // variance of each b_k
  const auto seedOnly = [&](size_t l) {
    return std::find(config.seedOnlyLengths.begin(), config.seedOnlyLengths.end(), config.pathLengths[l]) !=
           config.seedOnlyLengths.end();
  };
  // Evaluates candidates [from, to) of length slot l in parallel (each writes its own slot).
  const auto evaluate = [&](LengthBootstrap& lb, uint64_t from, uint64_t to) {
    lb.c.resize(to);
    if (binned) {
      lb.bin.resize(to, kNoBin);
      lb.work.resize(to, 0);
      if (config.luminance) lb.luminance.resize(to, -1);
    }
    const auto body = [&](const tbb::blocked_range<uint64_t>& r) {
      BinnedCandidateFn fn = makeCandidateFn();
      for (uint64_t i = r.begin(); i != r.end(); ++i) {
        CandidateInfo info;
        lb.c[i] = fn(lb.firstCandidate + i, lb.pathLength, &info);
        if (binned) {
          lb.bin[i] = info.bin;
          lb.work[i] = info.work;
          if (config.luminance) lb.luminance[i] = info.luminance;
        }
      }
    };
    if (config.parallel) tbb::parallel_for(tbb::blocked_range<uint64_t>(from, to, 1024), body);
    else body(tbb::blocked_range<uint64_t>(from, to));
    for (uint64_t i = from; i < to; ++i) {
      if (!(std::isfinite(lb.c[i]) && lb.c[i] >= 0))
        throw std::runtime_error("bootstrap: candidate " + std::to_string(lb.firstCandidate + i) +
                                 " has invalid target value " + std::to_string(lb.c[i]));
      if (!lb.luminance.empty() && !(std::isfinite(lb.luminance[i]) && lb.luminance[i] >= 0))
        throw std::runtime_error("bootstrap: candidate " + std::to_string(lb.firstCandidate + i) +
                                 " reported no valid luminance (" + std::to_string(lb.luminance[i]) + ")");
    }
  };
  // Sequential reductions in index order (bit-identical for any thread count).
  const auto reduce = [&](size_t l) {
    LengthBootstrap& lb = result.lengths[l];
    lb.estimate = summarizeCandidates(lb.c);
    varMean[l] = lb.estimate.stdErr * lb.estimate.stdErr;
    if (!lb.luminance.empty()) lb.luminanceEstimate = summarizeCandidates(lb.luminance);
  };
  for (size_t l = 0; l < config.pathLengths.size(); ++l) {
    LengthBootstrap lb;
    lb.pathLength = config.pathLengths[l];
    lb.firstCandidate = (config.firstSlot + uint64_t(l)) << kCandidateSlotBits;
    evaluate(lb, 0, N0);
    result.lengths.push_back(std::move(lb));
    reduce(l);
  }
  // Which sizing decisions below can depend on the candidates' values: the target's always; the budget's
  // only with several growable lengths (one length doubles while its first round's cost fits).
  size_t growableLengths = 0;
  for (size_t l = 0; l < config.pathLengths.size(); ++l) growableLengths += seedOnly(l) ? 0 : 1;
  const bool valueSized = config.totalCandidates > 0 ? growableLengths > 1 : config.targetRelStdErr > 0;
  if (config.totalCandidates > 0) {
    // Budgeted sizing, in cost (numbers drawn; all lengths alike for an unbinned bootstrap): the budget is
    // totalCandidates candidates of the chains' mix, as the first round measures it. Double the length
    // whose doubling removes most of b's variance per unit of cost (largest se_k^2 / (n_k cost_k); lowest
    // index on ties) while the total cost stays within the budget. A length's cost is that of its first
    // round, so that the decisions stay a pure function of the candidates' values and work.
    std::vector<double> cost(result.lengths.size());
    for (size_t l = 0; l < result.lengths.size(); ++l) cost[l] = candidateCost(result.lengths[l]);
    const double budget = double(config.totalCandidates) * chainMixCost(result.lengths);
    double spent = config.spentCost + bootstrapCost(result.lengths);
    for (;;) {
      size_t best = 0;
      const auto gain = [&](size_t l) {
        return seedOnly(l) ? 0.0 : varMean[l] / (double(result.lengths[l].c.size()) * cost[l]);
      };
      for (size_t l = 1; l < result.lengths.size(); ++l)
        if (gain(l) > gain(best)) best = l;
      LengthBootstrap& lb = result.lengths[best];
      const uint64_t n = lb.c.size();
      if (!(varMean[best] > 0) || spent + double(n) * cost[best] > budget) break;
      evaluate(lb, n, 2 * n);
      spent += double(n) * cost[best];
      reduce(best);
    }
  } else {
    // Sizing to a target: while b = sum b_k is not known to it, double the length that contributes most
    // to its variance (lowest index on ties). Once that length is at its cap, stop: growing lengths whose
    // variance is smaller cannot bring the total under the target as fast as it costs.
    for (;;) {
      double b = 0, var = 0;
      for (size_t l = 0; l < result.lengths.size(); ++l) {
        if (seedOnly(l)) continue;
        b += result.lengths[l].estimate.b;
        var += varMean[l];
      }
      if (!(config.targetRelStdErr > 0 && b > 0 && std::sqrt(var) > config.targetRelStdErr * b)) break;
      size_t worst = 0;
      const auto growable = [&](size_t l) { return seedOnly(l) ? 0.0 : varMean[l]; };
      for (size_t l = 1; l < result.lengths.size(); ++l)
        if (growable(l) > growable(worst)) worst = l;
      if (!(growable(worst) > 0)) break;
      if (result.lengths[worst].c.size() >= maxN) break;
      LengthBootstrap& lb = result.lengths[worst];
      const uint64_t n = lb.c.size();
      evaluate(lb, n, std::min(maxN, 2 * n));
      reduce(worst);
    }
  }
  double var = 0;
  for (size_t l = 0; l < result.lengths.size(); ++l) {
    LengthBootstrap& lb = result.lengths[l];
    lb.fixedCount = valueSized ? std::min<uint64_t>(N0, lb.c.size()) : lb.c.size();
    if (lb.fixedCount == lb.c.size()) {
      lb.fixedEstimate = lb.estimate;
      lb.fixedLuminanceEstimate = lb.luminanceEstimate;
    } else {
      lb.fixedEstimate = summarizeCandidates(lb.c.data(), lb.fixedCount);
      if (!lb.luminance.empty()) lb.fixedLuminanceEstimate = summarizeCandidates(lb.luminance.data(), lb.fixedCount);
    }
    if (lb.estimate.b > 0) lb.table = AliasTable(lb.c);
    result.b += lb.estimate.b;
    var += varMean[l];
    result.candidates += lb.c.size();
    if (lb.pathLength >= 0)
      spdlog::info("bootstrap: b_{} = {:.6g} +- {:.3g} ({:.2f}%) from {} candidates", lb.pathLength, lb.estimate.b, lb.estimate.stdErr,
                   lb.estimate.b > 0 ? 100 * lb.estimate.stdErr / lb.estimate.b : 0.0, lb.c.size());
  }
  result.bStdErr = std::sqrt(var);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("bootstrap: b = {:.6g} +- {:.3g} ({:.2f}%) from {} candidates in {:.2f} s", result.b, result.bStdErr,
               result.b > 0 ? 100 * result.bStdErr / result.b : 0.0, result.candidates, result.seconds);
  return result;
}

}  // namespace

double candidateCost(const LengthBootstrap& lb) {
  uint64_t work = 0;  // integers: exact
  for (uint32_t w : lb.work) work += w;
  return kCandidateOverhead + (lb.work.empty() ? 0.0 : double(work) / double(lb.work.size()));
}

double bootstrapCost(const std::vector<LengthBootstrap>& lengths) {
  double cost = 0;
  for (const LengthBootstrap& lb : lengths) cost += double(lb.c.size()) * candidateCost(lb);
  return cost;
}

double chainCost(const LengthBootstrap& lb) {
  const double uniform = candidateCost(lb);
  double c = 0, cWork = 0;  // in index order: deterministic
  for (size_t i = 0; i < lb.work.size() && i < lb.c.size(); ++i) {
    c += lb.c[i];
    cWork += lb.c[i] * double(lb.work[i]);
  }
  const double weighted = c > 0 ? kCandidateOverhead + cWork / c : uniform;
  return kCostLargeStepShare * uniform + (1 - kCostLargeStepShare) * weighted;
}

double chainMixCost(const std::vector<LengthBootstrap>& lengths) {
  if (lengths.empty()) return kCandidateOverhead;
  const std::vector<double> w = mutationWeights(lengths);
  double sumW = 0, wCost = 0, mean = 0;
  for (size_t l = 0; l < lengths.size(); ++l) {
    const double cost = chainCost(lengths[l]);
    sumW += w[l];
    wCost += w[l] * cost;
    mean += cost / double(lengths.size());
  }
  return sumW > 0 ? wCost / sumW : mean;
}

BootstrapResult runBootstrap(const BootstrapConfig& config, const CandidateFnFactory& makeCandidateFn) {
  return bootstrapImpl(config, [&makeCandidateFn]() -> BinnedCandidateFn {
    return [fn = makeCandidateFn()](uint64_t index, int pathLength, CandidateInfo*) { return fn(index, pathLength); };
  }, false);
}

BootstrapResult runBinnedBootstrap(const BootstrapConfig& config, const BinnedCandidateFnFactory& makeCandidateFn) {
  return bootstrapImpl(config, makeCandidateFn, true);
}

std::vector<uint64_t> apportion(uint64_t total, const std::vector<double>& weights) {
  std::vector<uint64_t> share(weights.size(), 0);
  double sum = 0;
  for (double w : weights) {
    if (!(std::isfinite(w) && w >= 0)) throw std::invalid_argument("apportion: invalid weight " + std::to_string(w));
    sum += w;
  }
  if (weights.empty() || !(sum > 0)) return share;
  std::vector<double> remainder(weights.size());
  uint64_t given = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    const double exact = double(total) * (weights[i] / sum);
    share[i] = static_cast<uint64_t>(std::floor(exact));
    remainder[i] = exact - double(share[i]);
    given += share[i];
  }
  // Rounding can overshoot by one in extreme cases; take back from the smallest remainders.
  std::vector<size_t> order(weights.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return remainder[a] > remainder[b]; });
  for (size_t j = 0; given < total; j = (j + 1) % order.size())
    if (weights[order[j]] > 0) { ++share[order[j]]; ++given; }
  for (size_t j = order.size(); given > total;) {
    j = (j == 0 ? order.size() : j) - 1;
    if (share[order[j]] > 0) { --share[order[j]]; --given; }
  }
  return share;
}

}  // namespace mlt
