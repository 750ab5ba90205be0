// Bootstrap pieces: the alias table samples its weights (chi-square), apportionment is exact and
// proportional, the bootstrap is bit-identical for any thread count, and develop's quantization makes
// merging exact.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "common/mlt/alias_table.h"
#include "common/mlt/bootstrap.h"
#include "common/mlt/develop.h"
#include "common/sampler/sample_source.h"
#include "tests/support/chi2.h"

namespace mlt {
namespace {

TEST(AliasTable, SamplesItsWeights) {
  Pcg32 rng(3, 4);
  std::vector<double> w(200);
  for (size_t i = 0; i < w.size(); ++i) w[i] = i % 7 == 0 ? 0.0 : std::pow(rng.uniformDouble(), 3);
  const AliasTable table(w);
  const int n = 1000000;
  std::vector<double> count(w.size(), 0);
  for (int i = 0; i < n; ++i) count[table.sample(rng.uniformDouble())] += 1;
  double stat = 0;
  int dof = -1;
  for (size_t i = 0; i < w.size(); ++i) {
    const double e = n * table.pmf(i);
    if (w[i] == 0) {
      EXPECT_EQ(count[i], 0) << "zero-weight index " << i << " sampled";
      continue;
    }
    stat += (count[i] - e) * (count[i] - e) / e;
    ++dof;
  }
  EXPECT_GT(test::chi2SurvivalProbability(stat, dof), 0.01);
}

TEST(AliasTable, RejectsBadWeights) {
  EXPECT_THROW(AliasTable(std::vector<double>{}), std::invalid_argument);
  EXPECT_THROW(AliasTable(std::vector<double>{0, 0}), std::invalid_argument);
  EXPECT_THROW(AliasTable(std::vector<double>{1, -1}), std::invalid_argument);
  EXPECT_THROW(AliasTable(std::vector<double>{1, NAN}), std::invalid_argument);
}

TEST(Apportion, ExactAndProportional) {
  Pcg32 rng(9, 9);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> w(1 + rng.bounded(8));
    for (double& x : w) x = rng.uniform() < 0.2f ? 0.0 : rng.uniformDouble();
    const uint64_t total = rng.bounded(100000);
    const std::vector<uint64_t> share = apportion(total, w);
    double sum = 0;
    for (double x : w) sum += x;
    uint64_t given = 0;
    for (size_t i = 0; i < w.size(); ++i) {
      given += share[i];
      if (sum > 0) {
        EXPECT_LT(std::fabs(double(share[i]) - total * w[i] / sum), 1.0) << trial;
      }
      if (w[i] == 0) {
        EXPECT_EQ(share[i], 0u);
      }
    }
    if (sum > 0) EXPECT_EQ(given, total);
  }
  EXPECT_EQ(apportion(10, {1, 1, 1}), (std::vector<uint64_t>{4, 3, 3}));  // ties to the lower index
}

BootstrapResult runWithThreads(int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  BootstrapConfig bc;
  bc.candidatesPerLength = 50000;
  bc.pathLengths = {2, 3, 4};
  return runBootstrap(bc, [] {
    return [](uint64_t i, int k) {
      const IndependentSource s(11, i);
      const double x = s.valueAt(0, 0), y = s.valueAt(1, 3);
      return x < 0.3 ? 0.0 : std::exp(k * x * y);  // some zeros, a per-length scale
    };
  });
}

TEST(Bootstrap, BitIdenticalForAnyThreadCount) {
  const BootstrapResult a = runWithThreads(1), b = runWithThreads(2), c = runWithThreads(8);
  for (const BootstrapResult* r : {&b, &c}) {
    ASSERT_EQ(r->lengths.size(), a.lengths.size());
    EXPECT_EQ(std::memcmp(&r->b, &a.b, sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(&r->bStdErr, &a.bStdErr, sizeof(double)), 0);
    for (size_t l = 0; l < a.lengths.size(); ++l) {
      EXPECT_EQ(r->lengths[l].c, a.lengths[l].c);
      EXPECT_EQ(std::memcmp(&r->lengths[l].estimate.b, &a.lengths[l].estimate.b, sizeof(double)), 0);
      for (int j = 0; j < 1000; ++j)
        EXPECT_EQ(r->lengths[l].table.sample(j / 1000.0), a.lengths[l].table.sample(j / 1000.0));
    }
  }
  // Candidates of different lengths are distinct numbers: slot l owns [l << 40, (l + 1) << 40).
  EXPECT_EQ(a.lengths[1].firstCandidate, uint64_t(1) << kCandidateSlotBits);
}

// The binned bootstrap is the same bootstrap, keeping every candidate's bin.
TEST(Bootstrap, BinnedEqualsUnbinned) {
  BootstrapConfig bc;
  bc.candidatesPerLength = 4096;
  bc.totalCandidates = 3 * 4096 * 4;
  bc.pathLengths = {1, 2, 3};
  const auto c = [](uint64_t i, int k) {
    const IndependentSource s(11, i);
    const double x = s.valueAt(0, 0), y = s.valueAt(1, 3);
    return x < 0.3 ? 0.0 : std::exp(k * x * y) * (y < 0.01 ? 50.0 : 1.0);
  };
  const BootstrapResult a = runBootstrap(bc, [&] { return CandidateFn(c); });
  const BootstrapResult b = runBinnedBootstrap(bc, [&]() -> BinnedCandidateFn {
    return [&](uint64_t i, int k, CandidateInfo* info) {
      info->bin = uint32_t(i % 7);  // no work reported: every length costs the same, as unbinned
      return c(i, k);
    };
  });
  ASSERT_EQ(a.lengths.size(), b.lengths.size());
  EXPECT_EQ(std::memcmp(&a.b, &b.b, sizeof(double)), 0);
  for (size_t l = 0; l < a.lengths.size(); ++l) {
    EXPECT_EQ(a.lengths[l].c, b.lengths[l].c);
    EXPECT_TRUE(a.lengths[l].bin.empty());
    ASSERT_EQ(b.lengths[l].bin.size(), b.lengths[l].c.size());
    for (size_t i = 0; i < b.lengths[l].bin.size(); ++i)
      EXPECT_EQ(b.lengths[l].bin[i], uint32_t((b.lengths[l].firstCandidate + i) % 7));
  }
}

TEST(Develop, QuantizedFilmsMergeExactlyInAnyGrouping) {
  std::vector<Film> films;
  Pcg32 rng(1, 1);
  for (int u = 0; u < 7; ++u) {
    Film f(8, 4);
    for (int i = 0; i < 300; ++i)
      f.addSplat(Vec2(rng.uniform() * 8, rng.uniform() * 4), Color(rng.uniform() * 3, rng.uniform(), rng.uniform() * 1e-7f));
    quantizeFilm(f, 5, u);
    films.push_back(f);
  }
  Film seq = films[0];
  for (int u = 1; u < 7; ++u) seq.merge(films[u]);
  Film left = films[0], right = films[4];
  for (int u = 1; u < 4; ++u) left.merge(films[u]);
  for (int u = 5; u < 7; ++u) right.merge(films[u]);
  left.merge(right);
  ASSERT_EQ(seq.splatSums().size(), left.splatSums().size());
  EXPECT_EQ(std::memcmp(seq.splatSums().data(), left.splatSums().data(), seq.splatSums().size() * sizeof(RGBd)), 0);
}

TEST(Develop, QuantizationIsUnbiased) {
  // A value far below the quantum survives in expectation (stochastic rounding).
  const double v = 0.3 * std::ldexp(1.0, -kQuantumExp);
  double sum = 0;
  const int n = 20000;
  for (int u = 0; u < n; ++u) {
    Film f(1, 1);
    f.splatSums()[0].r = v;
    quantizeFilm(f, 9, u);
    sum += f.splatSums()[0].r;
  }
  const double q = std::ldexp(1.0, -kQuantumExp);
  const double se = q * std::sqrt(0.3 * 0.7 / n);
  EXPECT_NEAR(sum / n, v, 4 * se);
}

// onQuantumGrid (read from the bits) against its definition, through ldexp and floor: the values that
// quantizeFilm makes, their neighbours one ulp away, both sides of every exponent where the test changes,
// zeros, subnormals, infinities, NaN and random bit patterns.
TEST(Develop, OnQuantumGridMatchesItsDefinition) {
  auto reference = [](double v) {
    if (!std::isfinite(v)) return false;
    const double scaled = std::ldexp(v, kQuantumExp);
    return std::isfinite(scaled) && scaled == std::floor(scaled);
  };
  std::vector<double> values = {0.0, -0.0, std::numeric_limits<double>::infinity(),
                                -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN(),
                                std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::max(),
                                std::numeric_limits<double>::min(), 0.1, 1.0 / 3.0};
  for (int e = -60; e <= 60; ++e)
    for (double m : {1.0, 1.5, 1.0 + 0x1p-52, 1.0 + 0x1p-26, 1.0 + 0x1p-25, 2.0 - 0x1p-52, 1.75})
      for (double sign : {1.0, -1.0}) {
        const double v = sign * std::ldexp(m, e);
        values.insert(values.end(), {v, std::nextafter(v, 0.0), std::nextafter(v, 1e300)});
      }
  Pcg32 rng(3, 7);
  int onGrid = 0;
  for (int i = 0; i < 200000; ++i) {
    Film f(1, 1);
    f.splatSums()[0].r = std::ldexp(rng.uniform(), int(rng.uniform() * 80) - 40);
    quantizeFilm(f, 11, uint64_t(i));
    values.push_back(f.splatSums()[0].r);
    const uint64_t bits = (uint64_t(rng.nextU32()) << 32) | rng.nextU32();
    double v;
    std::memcpy(&v, &bits, sizeof v);
    values.push_back(v);
  }
  for (double v : values) {
    ASSERT_EQ(onQuantumGrid(v), reference(v)) << std::hexfloat << v;
    onGrid += reference(v) ? 1 : 0;
  }
  EXPECT_GT(onGrid, 200000);  // every quantized value: both outcomes well represented
  EXPECT_GT(int(values.size()) - onGrid, 50000);
}

}  // namespace
}  // namespace mlt

namespace mlt {
namespace {

// Sizing from b's standard error: while b = sum b_k is not known to 1%, the length with the largest
// variance doubles. A rare, bright contribution (p = 0.5%, rel. error ~14/sqrt(N) of its b_k = 1) makes its
// length grow; a smooth one keeps the initial size; the cap holds; any thread count gives the same result.
BootstrapResult sizedBootstrap(int threads, uint64_t maxGrowth) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  BootstrapConfig bc;
  bc.candidatesPerLength = 20000;
  bc.pathLengths = {1, 2};
  bc.targetRelStdErr = 0.01;
  bc.maxGrowth = maxGrowth;
  return runBootstrap(bc, [] {
    return [](uint64_t i, int k) {
      const double u = IndependentSource(5, i).valueAt(0, 0);
      return k == 1 ? (u < 0.005 ? 200.0 : 0.0) : 1.0 + 0.1 * u;
    };
  });
}

double relStdErr(const BootstrapResult& r) { return r.bStdErr / r.b; }

TEST(Bootstrap, GrowsTheNoisiestLengthUntilBIsKnownToTheTarget) {
  const BootstrapResult capped = sizedBootstrap(2, 8);
  EXPECT_EQ(capped.lengths[0].c.size(), 8u * 20000u);  // the cap: not enough to reach 1%
  EXPECT_GT(relStdErr(capped), 0.01);
  EXPECT_EQ(capped.lengths[1].c.size(), 20000u);       // smooth: no growth
  EXPECT_EQ(capped.candidates, 9u * 20000u);

  const BootstrapResult wide = sizedBootstrap(2, 64);
  const LengthBootstrap& rare = wide.lengths[0];
  EXPECT_LE(relStdErr(wide), 0.01);                     // target met ...
  EXPECT_GT(rare.c.size(), 8u * 20000u);                // ... by doubling the rare length ...
  EXPECT_EQ(wide.lengths[1].c.size(), 20000u);          // ... alone
  // ... and it stopped at the first size that met it: with half of the rare candidates b was not known.
  const size_t half = rare.c.size() / 2;
  double sum = 0, sq = 0;
  for (size_t i = 0; i < half; ++i) sum += rare.c[i];
  const double bHalf = sum / double(half);
  for (size_t i = 0; i < half; ++i) sq += (rare.c[i] - bHalf) * (rare.c[i] - bHalf);
  const double varHalf = sq / (double(half) * double(half - 1)) + wide.lengths[1].estimate.stdErr * wide.lengths[1].estimate.stdErr;
  EXPECT_GT(std::sqrt(varHalf) / (bHalf + wide.lengths[1].estimate.b), 0.01);
  EXPECT_NEAR(rare.estimate.b, 0.005 * 200.0, 5 * rare.estimate.stdErr);

  const BootstrapResult one = sizedBootstrap(1, 64);
  EXPECT_EQ(one.lengths[0].c, rare.c);
  EXPECT_EQ(std::memcmp(&one.b, &wide.b, sizeof(double)), 0);
}

// Budgeted sizing (automatic bootstrap of mmlt): a quarter per length to start with, then doublings of the
// length whose b_k is least certain per candidate, within the total. The rare, bright length gets most of
// the budget, the smooth one keeps its start, the total never exceeds the budget.
TEST(Bootstrap, BudgetGoesToTheLengthWhoseBIsLeastCertain) {
  BootstrapConfig bc;
  bc.candidatesPerLength = 5000;
  bc.pathLengths = {1, 2};
  bc.totalCandidates = 40000;
  const BootstrapResult r = runBootstrap(bc, [] {
    return [](uint64_t i, int k) {
      const double u = IndependentSource(5, i).valueAt(0, 0);
      return k == 1 ? (u < 0.005 ? 200.0 : 0.0) : 1.0 + 0.1 * u;
    };
  });
  EXPECT_EQ(r.lengths[0].c.size(), 20000u);  // 5000 -> 10000 -> 20000; one more (+20000) would exceed 40000
  EXPECT_EQ(r.lengths[1].c.size(), 5000u);   // smooth: its start is enough
  EXPECT_EQ(r.candidates, 25000u);
}

// The budget counts cost, not candidates: two lengths as noisy as each other, one costing 9x the other
// per candidate (numbers drawn). The budget is totalCandidates of the chains' mix (the mean cost of the
// first round weighted as the plan allocates: by b_k here, where both lengths light the same bin) and the
// cost spent stays within it; the cheap length gets more of the doublings than it does when both cost the
// same.
TEST(Bootstrap, BudgetCountsTheCandidatesCost) {
  BootstrapConfig bc;
  bc.candidatesPerLength = 1024;
  bc.pathLengths = {1, 2};
  bc.totalCandidates = 16384;
  const auto value = [](uint64_t i) { return IndependentSource(5, i).valueAt(0, 0) < 0.02 ? 50.0 : 0.0; };
  const auto run = [&](uint32_t expensiveWork) {
    return runBinnedBootstrap(bc, [&]() -> BinnedCandidateFn {
      return [&, expensiveWork](uint64_t i, int k, CandidateInfo* info) {
        info->work = k == 2 ? expensiveWork : 0;
        info->bin = value(i) > 0 ? 0 : kNoBin;  // one film bin for both: the plan weighs them by b_k
        return value(i);
      };
    });
  };
  const BootstrapResult costed = run(8 * uint32_t(kCandidateOverhead));  // length 2: 9x the overhead alone
  const double c1 = candidateCost(costed.lengths[0]), c2 = candidateCost(costed.lengths[1]);
  EXPECT_DOUBLE_EQ(c1, kCandidateOverhead);
  EXPECT_DOUBLE_EQ(c2, 9 * kCandidateOverhead);
  const double bothB = costed.lengths[0].estimate.b + costed.lengths[1].estimate.b;
  const double mix = (costed.lengths[0].estimate.b * c1 + costed.lengths[1].estimate.b * c2) / bothB;
  EXPECT_NEAR(chainMixCost(costed.lengths), mix, 1e-12 * mix);
  const double spent = double(costed.lengths[0].c.size()) * c1 + double(costed.lengths[1].c.size()) * c2;
  EXPECT_LE(spent, double(bc.totalCandidates) * mix);
  EXPECT_GT(spent, 0.5 * double(bc.totalCandidates) * mix);  // within one doubling of the budget

  const BootstrapResult even = run(0);
  EXPECT_LE(even.candidates, bc.totalCandidates);
  EXPECT_GT(even.candidates, bc.totalCandidates / 2);
  // The optimum of sum se_k^2 at fixed cost is n_k ~ sigma_k / sqrt(cost_k): the cheap length's share grows
  // by about sqrt(9) = 3 (doublings quantize it to a power of two).
  const double ratioCosted = double(costed.lengths[0].c.size()) / double(costed.lengths[1].c.size());
  const double ratioEven = double(even.lengths[0].c.size()) / double(even.lengths[1].c.size());
  std::printf("n_1 / n_2: %g with costs 1 and 9, %g with equal costs\n", ratioCosted, ratioEven);
  EXPECT_GE(ratioCosted, 2 * ratioEven);
}

// The estimate the image is developed from (LengthBootstrap::fixedEstimate) is unbiased on a heavy tail; the
// sized bootstrap's own mean is not. The budget's doublings follow the candidates' values: a first round that
// missed a length's rare bright values looks certain and stops small with a low mean, one that caught them
// grows and dilutes them (optional stopping; cornell-spheres' mmlt: the bootstrap's b 3.7% low over 401
// runs). Three lengths, two of them a rare value of mean 1 (1 in 2000 and 1 in 200: a first round of 1024
// misses the rarer in 60% of runs), one smooth; 400 budgeted bootstraps, each with its own seed. The fixed
// estimates' mean lies within 4 standard errors of the exact b_k and b; the sized means' of the rarest length
// lies below by more than 4 (which shows that the runs exercise the bias the fixed estimate avoids).
TEST(Bootstrap, FixedCountEstimateIsUnbiasedOnAHeavyTail) {
  constexpr int kRuns = 400;
  const double exact[3] = {1.0, 1.0, 1.05};
  std::vector<double> sum(4, 0.0), sq(4, 0.0), sized(4, 0.0), sizedSq(4, 0.0);
  int grown = 0;
  for (int run = 0; run < kRuns; ++run) {
    BootstrapConfig bc;
    bc.candidatesPerLength = 1024;
    bc.pathLengths = {1, 2, 3};
    bc.totalCandidates = 3 * 4096;
    const uint64_t seed = 1000 + uint64_t(run);
    const BootstrapResult r = runBootstrap(bc, [seed] {
      return [seed](uint64_t i, int k) {
        const double u = IndependentSource(seed, i).valueAt(0, 0);
        return k == 1 ? (u < 1.0 / 2000 ? 2000.0 : 0.0) : k == 2 ? (u < 1.0 / 200 ? 200.0 : 0.0) : 1.0 + 0.1 * u;
      };
    });
    double fixedB = 0;
    for (int k = 0; k < 3; ++k) {
      const LengthBootstrap& lb = r.lengths[size_t(k)];
      ASSERT_EQ(lb.fixedCount, bc.candidatesPerLength);  // the first round: the only count no value decided
      ASSERT_EQ(lb.fixedEstimate.n, lb.fixedCount);
      grown += lb.c.size() > lb.fixedCount ? 1 : 0;
      sum[k] += lb.fixedEstimate.b;
      sq[k] += lb.fixedEstimate.b * lb.fixedEstimate.b;
      sized[k] += lb.estimate.b;
      sizedSq[k] += lb.estimate.b * lb.estimate.b;
      fixedB += lb.fixedEstimate.b;
    }
    sum[3] += fixedB;
    sq[3] += fixedB * fixedB;
    sized[3] += r.b;
    sizedSq[3] += r.b * r.b;
  }
  EXPECT_GT(grown, kRuns);  // the sizing grew lengths (else the first round would be every candidate)
  const auto meanSe = [&](const std::vector<double>& s, const std::vector<double>& q, int k) {
    const double mean = s[size_t(k)] / kRuns;
    return std::pair{mean, std::sqrt((q[size_t(k)] / kRuns - mean * mean) / (kRuns - 1))};
  };
  for (int k = 0; k < 4; ++k) {
    const std::string name = k < 3 ? "b_" + std::to_string(k + 1) : std::string("b");
    const double want = k < 3 ? exact[k] : exact[0] + exact[1] + exact[2];
    const auto [mean, se] = meanSe(sum, sq, k);
    const auto [sizedMean, sizedSe] = meanSe(sized, sizedSq, k);
    std::printf("%s: fixed count %.4f +- %.4f (%+.1f s.e.), sized %.4f +- %.4f (%+.1f s.e.); exact %.4f\n",
                name.c_str(), mean, se, (mean - want) / se, sizedMean, sizedSe, (sizedMean - want) / sizedSe, want);
    EXPECT_LT(std::fabs(mean - want), 4 * se) << name;
    if (k == 0) {
      EXPECT_LT(sizedMean, want - 4 * sizedSe) << name;
    }
  }
}

// With one length the budget's doublings depend on its first round's cost alone, never on its values: every
// candidate counts (fixedCount = all of them, the same estimate).
TEST(Bootstrap, OneLengthKeepsEveryCandidateForTheImage) {
  BootstrapConfig bc;
  bc.candidatesPerLength = 1024;
  bc.pathLengths = {-1};
  bc.totalCandidates = 8192;
  const BootstrapResult r = runBootstrap(bc, [] {
    return [](uint64_t i, int) { return IndependentSource(7, i).valueAt(0, 0) < 0.01 ? 100.0 : 0.0; };
  });
  const LengthBootstrap& lb = r.lengths.front();
  EXPECT_GT(lb.c.size(), bc.candidatesPerLength);
  EXPECT_EQ(lb.fixedCount, lb.c.size());
  EXPECT_EQ(lb.fixedEstimate, lb.estimate);
}

}  // namespace

// Cost spent outside the candidates (mmlt's b_1 camera rays, BootstrapConfig::spentCost) comes out of
// the budget: all of it spent, no length doubles; half of it, fewer doublings than with none, and the
// candidates' cost fits in the half that is left.
TEST(Bootstrap, SpentCostComesOutOfTheBudget) {
  BootstrapConfig bc;
  bc.candidatesPerLength = 1024;
  bc.pathLengths = {1, 2};
  bc.totalCandidates = 32768;
  const BinnedCandidateFnFactory candidates = []() -> BinnedCandidateFn {
    return [](uint64_t i, int, CandidateInfo* info) {
      info->work = 3;
      const double c = IndependentSource(5, i).valueAt(0, 0) < 0.02 ? 50.0 : 0.0;
      info->bin = c > 0 ? 0 : kNoBin;
      return c;
    };
  };
  const BootstrapResult none = runBinnedBootstrap(bc, candidates);
  const double budget = double(bc.totalCandidates) * chainMixCost(none.lengths);  // as the first round prices it
  const auto run = [&](double spentFraction) {
    BootstrapConfig c = bc;
    c.spentCost = spentFraction * budget;
    return runBinnedBootstrap(c, candidates);
  };
  const BootstrapResult half = run(0.5), all = run(1.0);
  EXPECT_EQ(all.candidates, 2 * bc.candidatesPerLength);  // the first round only
  EXPECT_LT(half.candidates, none.candidates);
  EXPECT_GT(half.candidates, all.candidates);
  EXPECT_LE(bootstrapCost(half.lengths), 0.5 * budget);
}

}  // namespace mlt
