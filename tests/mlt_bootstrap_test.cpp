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

// Sizing from b's standard error: while b = sum b_k is not predicted to be known to 1%, the length with
// the largest predicted variance doubles its fresh candidates (after the first round of 20000, which sizes
// and is not counted in b_k: bootstrap.h). A rare, bright contribution (p = 0.5%, rel. error ~14/sqrt(N) of
// its b_k = 1) makes its length grow; a smooth one keeps one fresh round; the cap holds; any thread count
// gives the same result.
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
  EXPECT_EQ(capped.lengths[0].estimate.n, 8u * 20000u);  // the cap: not enough to reach 1%
  EXPECT_EQ(capped.lengths[0].c.size(), 9u * 20000u);    // the first round and the fresh ones
  EXPECT_EQ(capped.lengths[0].estimateFrom, 20000u);
  EXPECT_GT(relStdErr(capped), 0.01);
  EXPECT_EQ(capped.lengths[1].estimate.n, 20000u);       // smooth: one fresh round, no growth
  EXPECT_EQ(capped.candidates, 11u * 20000u);

  const BootstrapResult wide = sizedBootstrap(2, 64);
  const LengthBootstrap& rare = wide.lengths[0];
  EXPECT_GT(rare.estimate.n, 8u * 20000u);               // the rare length doubled ...
  EXPECT_EQ(wide.lengths[1].estimate.n, 20000u);         // ... alone
  // ... and stopped at the first size the first round predicted to meet 1%: sigma_k^2 / n_k from the first
  // round's per-candidate variance, at n and n / 2.
  const BootstrapEstimate first = summarizeCandidates(rare.c.data(), 20000);
  const BootstrapEstimate firstSmooth = summarizeCandidates(wide.lengths[1].c.data(), 20000);
  const double s2 = first.stdErr * first.stdErr * 20000, s2Smooth = firstSmooth.stdErr * firstSmooth.stdErr * 20000;
  const double n = double(rare.estimate.n), b = first.b + firstSmooth.b;
  EXPECT_LE(std::sqrt(s2 / n + s2Smooth / 20000) / b, 0.01);
  EXPECT_GT(std::sqrt(s2 / (n / 2) + s2Smooth / 20000) / b, 0.01);
  EXPECT_LT(relStdErr(wide), 0.0125);  // the prediction holds roughly for the fresh candidates too
  EXPECT_NEAR(rare.estimate.b, 0.005 * 200.0, 5 * rare.estimate.stdErr);

  const BootstrapResult one = sizedBootstrap(1, 64);
  EXPECT_EQ(one.lengths[0].c, rare.c);
  EXPECT_EQ(std::memcmp(&one.b, &wide.b, sizeof(double)), 0);
}

// Budgeted sizing (automatic bootstrap of mmlt): a quarter per length to start with (the first round), a
// first round's worth of fresh candidates each, then doublings of the length whose b_k is least certain
// per candidate, within the total, and the rest of the budget to it. The rare, bright length gets most of
// the budget, the smooth one one fresh round, the total is the budget.
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
  // 2 x 5000 first, 2 x 5008 fresh (whole groups of 16): 20016; the rare length 5008 -> 10016 -> 20032
  // (35040; one more, +20032, would exceed 40000), then the 4960 left: 24992.
  EXPECT_EQ(r.lengths[0].estimate.n, 24992u);
  EXPECT_EQ(r.lengths[0].c.size(), 5000u + 24992u);
  EXPECT_EQ(r.lengths[1].estimate.n, 5008u);  // smooth: one fresh round is enough
  EXPECT_EQ(r.candidates, 40000u);
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
  // The budget, priced by the first round (its b_k weigh the mix).
  const double b1 = summarizeCandidates(costed.lengths[0].c.data(), bc.candidatesPerLength).b;
  const double b2 = summarizeCandidates(costed.lengths[1].c.data(), bc.candidatesPerLength).b;
  const double budget = double(bc.totalCandidates) * (b1 * c1 + b2 * c2) / (b1 + b2);
  const double spent = double(costed.lengths[0].c.size()) * c1 + double(costed.lengths[1].c.size()) * c2;
  EXPECT_LE(spent, budget);
  EXPECT_GT(spent, budget - 16 * c2);  // the rest of the budget, in whole groups

  const BootstrapResult even = run(0);
  EXPECT_LE(even.candidates, bc.totalCandidates);
  EXPECT_GT(even.candidates, bc.totalCandidates - 16);
  // The optimum of sum se_k^2 at fixed cost is n_k ~ sigma_k / sqrt(cost_k): the cheap length's share grows
  // by about sqrt(9) = 3 (doublings quantize it to a power of two).
  const double ratioCosted = double(costed.lengths[0].estimate.n) / double(costed.lengths[1].estimate.n);
  const double ratioEven = double(even.lengths[0].estimate.n) / double(even.lengths[1].estimate.n);
  std::printf("n_1 / n_2: %g with costs 1 and 9, %g with equal costs\n", ratioCosted, ratioEven);
  EXPECT_GE(ratioCosted, 2 * ratioEven);
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
  // the first round and one fresh round's worth: b_k needs fresh candidates however little is left
  EXPECT_EQ(all.candidates, 2 * 2 * bc.candidatesPerLength);
  EXPECT_LT(half.candidates, none.candidates);
  EXPECT_GT(half.candidates, all.candidates);
  EXPECT_LE(bootstrapCost(half.lengths), 0.5 * budget);
}

}  // namespace mlt

namespace mlt {
namespace {

// A sized bootstrap's b is unbiased. Its sizing looks at the candidates' values (a length whose candidates
// spread more gets more of them), so a length's count depends on what its first candidates held; b_k must
// then come from candidates whose count was fixed before they were drawn, or it leans low on a heavy
// tail: a first round that missed the rare bright paths looks certain and stops small with a low mean,
// one that caught them grows and dilutes them (cornell-spheres' mmlt: b_k 3-15% low on average over 401
// runs, the image 0.14% low; docs/CHAINS.md). Three lengths, two of them a rare value of mean 1 (1 in 2000
// and 1 in 200: a first round of 1024 misses the rarer in 60% of runs), one smooth; 400 runs of a budgeted
// bootstrap, each with its own seed: their mean b within 4 standard errors of the exact 3.05, and so is each
// length's.
TEST(Bootstrap, SizedBIsUnbiasedOnAHeavyTail) {
  constexpr int kRuns = 400;
  const double exact[3] = {1.0, 1.0, 1.05};
  std::vector<double> sum(4, 0.0), sq(4, 0.0);
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
    for (int k = 0; k < 3; ++k) {
      sum[k] += r.lengths[k].estimate.b;
      sq[k] += r.lengths[k].estimate.b * r.lengths[k].estimate.b;
    }
    sum[3] += r.b;
    sq[3] += r.b * r.b;
  }
  for (int k = 0; k < 4; ++k) {
    const double mean = sum[k] / kRuns, se = std::sqrt((sq[k] / kRuns - mean * mean) / (kRuns - 1));
    const double want = k < 3 ? exact[k] : exact[0] + exact[1] + exact[2];
    std::printf("%s: mean %.4f +- %.4f over %d runs, exact %.4f (%+.1f s.e.)\n",
                k < 3 ? ("b_" + std::to_string(k + 1)).c_str() : "b", mean, se, kRuns, want, (mean - want) / se);
    EXPECT_LT(std::fabs(mean - want), 4 * se) << (k < 3 ? "b_" + std::to_string(k + 1) : std::string("b"));
  }
}

}  // namespace
}  // namespace mlt
