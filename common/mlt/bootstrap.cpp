#include "common/mlt/bootstrap.h"

#include "common/mlt/allocation.h"

#include <fmt/format.h>
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
  // The most candidates a length may hold: its slot of candidate indices, or with a target the first round
  // and maxGrowth x N0 fresh ones.
  const uint64_t slot = (uint64_t(1) << kCandidateSlotBits) - 1;
  const bool sized = config.totalCandidates > 0 || (config.targetRelStdErr > 0 && config.maxGrowth > 1);
  const uint64_t maxN = config.totalCandidates > 0 ? slot : config.maxGrowth > 1 ? N0 * (config.maxGrowth + 1) : N0;
  if (maxN > slot || (sized && 2 * N0 + kCandidateGroups > slot))
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
  // Sequential reductions in index order (bit-identical for any thread count). A length's estimate
  // summarizes its candidates [from, c.size()).
  const auto reduce = [&](size_t l, uint64_t from) {
    LengthBootstrap& lb = result.lengths[l];
    lb.estimateFrom = from;
    lb.estimate = summarizeCandidates(lb.c.data() + from, lb.c.size() - from);
    varMean[l] = lb.estimate.stdErr * lb.estimate.stdErr;
    if (!lb.luminance.empty()) lb.luminanceEstimate = summarizeCandidates(lb.luminance.data() + from, lb.luminance.size() - from);
  };
  // The first round: N0 candidates per length, a count fixed in advance.
  for (size_t l = 0; l < config.pathLengths.size(); ++l) {
    LengthBootstrap lb;
    lb.pathLength = config.pathLengths[l];
    lb.firstCandidate = (config.firstSlot + uint64_t(l)) << kCandidateSlotBits;
    evaluate(lb, 0, N0);
    result.lengths.push_back(std::move(lb));
    reduce(l, 0);
  }
  if (sized) {
    // Sizing (bootstrap.h): the first round decides how many more candidates each length gets, from its
    // per-candidate variance s2_l = N0 se_l^2 (the groups' spread: it keeps the film positions' stratification)
    // and its cost, predicting se_l^2 = s2_l / f_l for f_l fresh candidates. Then the fresh ones are drawn and
    // b_l is their mean alone: their count was fixed before any of them was seen. (Counting the first round
    // too biased b low: a first round that missed the rare bright paths looks certain, stops small and keeps
    // its low mean, one that caught them grows and dilutes them; on cornell-spheres' mmlt b_k was 3-15% low
    // on average: tests/mlt_bootstrap_test.cpp, SizedBIsUnbiasedOnAHeavyTail, and docs/CHAINS.md.) The
    // first round still seeds chains (the alias table holds every candidate) and prices the budget.
    const uint64_t G = kCandidateGroups;
    const uint64_t start = (N0 + G - 1) / G * G;  // fresh counts in whole randomization groups
    std::vector<double> s2(result.lengths.size()), fresh(result.lengths.size(), 0.0);
    for (size_t l = 0; l < result.lengths.size(); ++l) {
      s2[l] = varMean[l] * double(N0);
      if (!seedOnly(l)) fresh[l] = double(start);
    }
    const auto cap = [&](size_t l) { return double(maxN) - double(N0) - fresh[l]; };  // room left in the slot
    if (config.totalCandidates > 0) {
      // A budget: every length's first fresh round, then doublings of the length whose doubling removes most
      // of b's predicted variance per unit of cost (largest s2_l / (f_l^2 cost_l); lowest index on ties)
      // while the total cost fits, then what is left to that length in whole groups.
      std::vector<double> cost(result.lengths.size());
      for (size_t l = 0; l < result.lengths.size(); ++l) cost[l] = candidateCost(result.lengths[l]);
      const double budget = double(config.totalCandidates) * chainMixCost(result.lengths);
      double spent = config.spentCost + bootstrapCost(result.lengths);
      for (size_t l = 0; l < result.lengths.size(); ++l) spent += fresh[l] * cost[l];
      const auto gain = [&](size_t l) {
        return fresh[l] > 0 && s2[l] > 0 ? s2[l] / (fresh[l] * fresh[l] * cost[l]) : 0.0;
      };
      size_t best = 0;
      for (;;) {
        best = 0;
        for (size_t l = 1; l < result.lengths.size(); ++l)
          if (gain(l) > gain(best)) best = l;
        if (!(gain(best) > 0) || spent + fresh[best] * cost[best] > budget || fresh[best] > cap(best)) break;
        spent += fresh[best] * cost[best];
        fresh[best] *= 2;
      }
      if (gain(best) > 0 && budget > spent) {
        const double more = std::min(std::floor((budget - spent) / (cost[best] * double(G))) * double(G), cap(best));
        if (more > 0) fresh[best] += std::floor(more / double(G)) * double(G);
      }
    } else {
      // A target: while b's predicted relative standard error exceeds it, the length with the largest
      // predicted variance doubles, up to maxGrowth x N0 fresh candidates (maxN).
      const double b = [&] {
        double sum = 0;
        for (size_t l = 0; l < result.lengths.size(); ++l) sum += seedOnly(l) ? 0.0 : result.lengths[l].estimate.b;
        return sum;
      }();
      const auto var = [&](size_t l) { return fresh[l] > 0 ? s2[l] / fresh[l] : 0.0; };
      for (;;) {
        double total = 0;
        size_t worst = 0;
        for (size_t l = 0; l < result.lengths.size(); ++l) {
          total += var(l);
          if (var(l) > var(worst)) worst = l;
        }
        if (!(b > 0 && std::sqrt(total) > config.targetRelStdErr * b && var(worst) > 0)) break;
        if (fresh[worst] > cap(worst)) break;
        fresh[worst] *= 2;
      }
    }
    for (size_t l = 0; l < result.lengths.size(); ++l) {
      if (!(fresh[l] > 0)) continue;
      evaluate(result.lengths[l], N0, N0 + uint64_t(fresh[l]));
      reduce(l, N0);
    }
  }
  double var = 0;
  for (size_t l = 0; l < result.lengths.size(); ++l) {
    LengthBootstrap& lb = result.lengths[l];
    if (lb.estimate.b > 0) lb.table = AliasTable(lb.c);
    result.b += lb.estimate.b;
    var += varMean[l];
    result.candidates += lb.c.size();
    if (lb.pathLength >= 0)
      spdlog::info("bootstrap: b_{} = {:.6g} +- {:.3g} ({:.2f}%) from {} candidates{}", lb.pathLength, lb.estimate.b,
                   lb.estimate.stdErr, lb.estimate.b > 0 ? 100 * lb.estimate.stdErr / lb.estimate.b : 0.0,
                   lb.estimate.n, lb.estimateFrom > 0 ? fmt::format(" (and {} that sized it)", lb.estimateFrom) : "");
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
