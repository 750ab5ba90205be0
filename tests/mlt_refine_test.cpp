// b refined as the job runs (common/mlt/develop.h (D3)-(D5)): the chains' large steps are independent
// uniform samples of the target, their sums merge exactly, the pooled b's standard error shrinks as the
// job grows, the bootstrap is sized to a small share of the job, and normalization happens only when
// the image is developed (one film layer per path length).
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "common/core/rng.h"
#include "common/methods/pss_method.h"
#include "common/methods/registry.h"
#include "common/methods/chain_report.h"
#include "common/mlt/bootstrap.h"
#include "common/mlt/develop.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(16, 12));
  return *scene;
}

RenderSettings settingsFor(std::string m, uint64_t seed, double mpp) {
  RenderSettings s;
  s.directLight = DirectLight::Chains;  // chains over every length (the automatic choice: direct_light_rule_test)
  s.method = m;
  s.seed = seed;
  s.integrator.maxDepth = 4;
  s.mutationsPerPixel = mpp;
  s.bootstrapSamples = 4096;
  s.chains = 16;
  return s;
}

PartialResult runJob(const JobPlan& plan) {
  std::vector<PartialResult> parts(plan.units.size());
  tbb::parallel_for(size_t(0), plan.units.size(),
                    [&](size_t i) { parts[i] = runWorkUnit(cornell(), plan, plan.units[i]); });
  PartialResult merged;
  for (const PartialResult& p : parts) merged.add(p);
  return merged;
}

TEST(RefinedB, PooledEstimateIsTheMeanAndStandardErrorOfAllSamples) {
  Pcg32 rng(11, 3);
  std::vector<double> a(1000), b(3000);
  TargetSums sa, sb;
  for (double& c : a) sa.add(c = -std::log(1 - rng.uniformDouble()));  // exponential, mean 1
  for (double& c : b) sb.add(c = -std::log(1 - rng.uniformDouble()));
  std::vector<double> all = a;
  all.insert(all.end(), b.begin(), b.end());
  double mean = 0, var = 0;
  for (double c : all) mean += c;
  mean /= double(all.size());
  for (double c : all) var += (c - mean) * (c - mean);
  var /= double(all.size() - 1);
  const BEstimate e = pooledB(sa, sb);
  EXPECT_EQ(e.samples, 4000u);
  EXPECT_NEAR(e.b, mean, 1e-12);
  EXPECT_NEAR(e.stdErr, std::sqrt(var / double(all.size())), 1e-9);
  EXPECT_EQ(pooledB({}, {}).b, 0.0);
}

// A bootstrap without a tail (tau = infinity: the bulk is all of c).
BootstrapEstimate unsplit(uint64_t n, double b, double stdErr, double sampleVar) {
  return {n, b, stdErr, sampleVar, std::numeric_limits<double>::infinity(), b, stdErr, sampleVar, 0.0};
}

TEST(RefinedB, BulkWeighsByTheBootstrapsModelAndReportsTheLargerError) {
  const BootstrapEstimate boot = unsplit(1000, 2.0, 0.1, 40.0);  // sampleVar 40: a large step's variance
  TargetSums large;
  large.n = 4000;
  large.sum = large.bulk = 4000 * 2.3;
  large.sumSq = large.bulkSq = 4000 * (2.3 * 2.3 + 20.0);  // their own spread (~20) is below the model's 40
  const BEstimate e = combineB(boot, large);
  const double v0 = 0.01, vL = 40.0 / 4000;  // equal variances: equal weights
  EXPECT_NEAR(e.b, 0.5 * 2.0 + 0.5 * 2.3, 1e-12);
  EXPECT_NEAR(e.stdErr, std::sqrt(v0 * vL / (v0 + vL)), 1e-12);
  // A heavy tail the bootstrap missed: the large steps' spread (variance ~400) never enters the weights, but
  // it does enter the standard error: w0^2 v0 + (1 - w0)^2 S2 / n_L.
  TargetSums tail = large;
  tail.sumSq = tail.bulkSq = 4000 * (2.3 * 2.3 + 400.0);
  const BEstimate t = combineB(boot, tail);
  EXPECT_EQ(t.b, e.b);
  const double s2 = (tail.sumSq - 4000 * 2.3 * 2.3) / 3999 / 4000;
  EXPECT_NEAR(t.stdErr, std::sqrt(0.25 * v0 + 0.25 * s2), 1e-12);
  EXPECT_GT(t.stdErr, 2 * e.stdErr);
  EXPECT_EQ(e.samples, 5000u);
  EXPECT_EQ(combineB(boot, {}).b, 2.0);  // no large steps yet: the bootstrap's
  EXPECT_EQ(combineB(unsplit(1000, 1.0, 0.0, 0.0), large).b, (1000 * 1.0 + 4000 * 2.3) / 5000);  // both exact: by count
  EXPECT_EQ(combineB(unsplit(1000, 1.0, 0.0, 1.0), large).b, 1.0);  // an exact bootstrap wins
}

// Without a tail threshold (tau = infinity: mmlt's b_1 from camera rays) the large steps' sum and bulk are
// the same numbers, rounded independently by quantizeSums: a difference of one quantum must neither add an
// excess nor make the stated standard error infinite (the covariance term is excess * (tau - m)). Seen with
// a target whose values are not floats: the EXR said bStdErr = inf.
TEST(RefinedB, NoThresholdNoExcessWhateverTheRounding) {
  const BootstrapEstimate boot = unsplit(1000, 2.0, 0.1, 40.0);
  TargetSums large;
  large.n = 4000;
  large.bulk = 4000 * 2.3;
  large.sum = large.bulk + 0x1p-30;  // rounded up where the bulk was rounded down
  large.sumSq = large.bulkSq = 4000 * (2.3 * 2.3 + 20.0);
  TargetSums same = large;
  same.sum = same.bulk;
  const BEstimate e = combineB(boot, large), exact = combineB(boot, same);
  EXPECT_TRUE(std::isfinite(e.stdErr)) << e.stdErr;
  EXPECT_EQ(e.stdErr, exact.stdErr);
  EXPECT_EQ(e.b, exact.b);
}

TEST(RefinedB, ExcessAboveTheTailThresholdIsPooledByCount) {
  // The same bulk as above, plus an excess: 1000 bootstrap candidates with a mean excess 0.5, 4000 large
  // steps with 0.1. The excess's estimate is the pooled mean (1000 * 0.5 + 4000 * 0.1) / 5000 = 0.18,
  // whatever the bulk's weights, and it adds to the bulk's estimate.
  BootstrapEstimate boot = unsplit(1000, 2.5, 0.1, 40.0);
  boot.tau = 10;
  boot.bulkB = 2.0;
  boot.excessMeanSq = 0.5 * 50;  // every 100th candidate has an excess of 50
  TargetSums large;
  large.n = 4000;
  large.bulk = 4000 * 2.3;
  large.sum = large.bulk + 4000 * 0.1;
  large.bulkSq = 4000 * (2.3 * 2.3 + 20.0);
  large.excessSq = 4000 * 0.1 * 50;
  const BEstimate e = combineB(boot, large);
  EXPECT_NEAR(e.b, 0.5 * 2.0 + 0.5 * 2.3 + 0.18, 1e-12);
  const double bulkSe = std::sqrt(0.01 * 0.01 / 0.02);
  const double n = 5000, excessVar = (1000 * 25.0 + 4000 * 5.0 - n * 0.18 * 0.18) / (n - 1) / n;
  const double cov = 0.18 * (10 - (1000 * 2.0 + 4000 * 2.3) / n) / n;  // per sample E[e] (tau - E[m]), / n
  EXPECT_NEAR(e.stdErr, std::sqrt(bulkSe * bulkSe + excessVar + 2 * cov), 1e-12);
}

TEST(RefinedB, SummaryOfCandidatesSplitsTheTail) {
  std::vector<double> c(16 * 1024);
  Pcg32 rng(3, 9);
  for (double& x : c) x = -std::log(1 - rng.uniformDouble());
  c[77] = 1e4;  // one bright outlier
  const BootstrapEstimate e = summarizeCandidates(c);
  std::vector<double> sorted = c;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(e.tau, sorted[c.size() - tailCandidates(c.size())]);
  double bulk = 0, excess = 0;
  for (double x : c) {
    bulk += std::min(x, e.tau);
    excess += (x - std::min(x, e.tau)) * (x - std::min(x, e.tau));
  }
  EXPECT_NEAR(e.bulkB, bulk / double(c.size()), 1e-12);
  EXPECT_NEAR(e.excessMeanSq, excess / double(c.size()), 1e-6);
  EXPECT_GT(e.b, e.bulkB + 1e4 / double(c.size()) * 0.99);  // the outlier is in the excess
  EXPECT_LT(e.bulkStdErr, 0.1 * e.stdErr);                  // and not in the bulk's spread
  EXPECT_EQ(summarizeCandidates(std::vector<double>(16, 1.0)).tau, std::numeric_limits<double>::infinity());
}

// A synthetic target like the scenes' (the bright, stratified bulk of the image and a rare, very bright
// tail: caustics through a mirror): the bootstrap's candidates are 16 independent randomizations of a
// stratified set, the large steps i.i.d. Returns c for candidate `i` of `n` (group i % 16).
struct StratifiedTail {
  static constexpr double p = 1e-5, v = 2000;  // the tail: probability and value; the mean of c is 1
  double bulk(double u) const { return -std::log1p(-u) * (1 - p * v); }  // exponential, mean 1 - p v
  double tail(Pcg32& rng) const { return rng.uniformDouble() < p ? v : 0.0; }
};

TEST(RefinedB, CombinedBIsUnbiasedForAHeavyTailedStratifiedTarget) {
  // Inverse-variance weights estimated from the bootstrap (the rule before) put more weight on a bootstrap
  // that missed the tail (small spread, low mean) than on one that caught it, so their b is low on
  // average (-1.3% here: 30 standard errors of this test). With the tail split the weights see the bulk
  // only and the excess is pooled by count: unbiased.
  const StratifiedTail target;
  const uint64_t G = kCandidateGroups, N0 = G * 1024, NL = 6 * N0;
  const int trials = 2000;
  double sumNew = 0, sumSqNew = 0, sumOld = 0;
  for (int trial = 0; trial < trials; ++trial) {
    Pcg32 rng(uint64_t(trial), 17);
    std::vector<double> c(N0);
    std::vector<double> shift(G);
    for (double& s : shift) s = rng.uniformDouble();
    for (uint64_t i = 0; i < N0; ++i) {  // group i % G: row i / G of a shifted lattice (stratified)
      const double u = (double(i / G) + shift[i % G]) / double(N0 / G);
      c[i] = target.bulk(std::min(u, 1 - 1e-16)) + target.tail(rng);
    }
    const BootstrapEstimate boot = summarizeCandidates(c);
    TargetSums large;
    for (uint64_t i = 0; i < NL; ++i) large.add(target.bulk(rng.uniformDouble()) + target.tail(rng), boot.tau);
    const double b = combineB(boot, large).b;
    sumNew += b;
    sumSqNew += b * b;
    const double vL = boot.sampleVar / double(NL), v0 = boot.stdErr * boot.stdErr;  // the rule before
    const double w = vL / (v0 + vL);
    sumOld += w * boot.b + (1 - w) * large.sum / double(NL);
  }
  const double mean = sumNew / trials;
  const double se = std::sqrt(std::max(0.0, sumSqNew / trials - mean * mean) / trials);
  std::printf("b over %d trials (true 1): tail split %.5f +- %.5f, inverse-variance weights %.5f\n", trials,
              mean, se, sumOld / trials);
  EXPECT_NEAR(mean, 1.0, 4 * se) << "tail-split b: mean " << mean << " +- " << se;
  EXPECT_LT(sumOld / trials, 1.0 - 8 * se) << "the value-weighted rule is biased low here (it is what this test guards against)";
}

TEST(RefinedB, CandidatesSpreadTheirFirstDecisionsAndStayUniform) {
  // Every group's first n points cover the film evenly: each of the 8x8 cells gets n/64 +- 2 of 16 * 1024.
  std::vector<int> cells(64, 0);
  for (uint64_t i = 0; i < 16 * 1024; ++i) {
    const IndependentSource c = IndependentSource::candidate(3, (uint64_t(2) << kCandidateSlotBits) + i);
    const float x = c.valueAt(int(Stream::Camera), 0), y = c.valueAt(int(Stream::Camera), 1);
    ASSERT_TRUE(x >= 0 && x < 1 && y >= 0 && y < 1);
    ++cells[int(x * 8) * 8 + int(y * 8)];
  }
  for (int n : cells) EXPECT_NEAR(n, 256, 2 * 16);
  // Other coordinates are the independent source's; the technique and the light's are spread too.
  EXPECT_EQ(IndependentSource::candidate(3, 77).valueAt(int(Stream::Camera), 2), IndependentSource(3, 77).valueAt(int(Stream::Camera), 2));
  EXPECT_EQ(IndependentSource::candidate(3, 77).valueAt(int(Stream::Light), 5), IndependentSource(3, 77).valueAt(int(Stream::Light), 5));
  EXPECT_EQ(IndependentSource::candidate(3, 77).valueAt(int(Stream::Connect), 0), candidateCoordinate(3, 77, 2));
  EXPECT_EQ(IndependentSource::candidate(3, 77).valueAt(int(Stream::Light), 4), candidateCoordinate(3, 77, 7));
  std::vector<int> techniques(5, 0);  // base 5: 1024 points of one group fill 5 bins evenly (i.i.d.: +-13)
  for (uint64_t i = 0; i < 16 * 1024; i += 16) ++techniques[int(candidateCoordinate(3, i, 2) * 5)];
  for (int n : techniques) EXPECT_NEAR(n, 1024 / 5.0, 5);
  // Over randomizations (seeds), one candidate's position is uniform: a chi-square over 16 bins.
  std::vector<int> bins(16, 0);
  const int n = 16000;
  for (int seed = 0; seed < n; ++seed) ++bins[int(IndependentSource::candidate(uint64_t(seed), 5).valueAt(0, 0) * 16)];
  double chi2 = 0;
  for (int b : bins) chi2 += (b - n / 16.0) * (b - n / 16.0) / (n / 16.0);
  EXPECT_LT(chi2, 37.7);  // 15 degrees of freedom, p = 0.001
}

TEST(RefinedB, LargeStepsSampleTheTargetLikeTheBootstrap) {
  // The large steps' mean of c per path length agrees with the bootstrap's b_k within their combined
  // standard error: a chain that counted accepted large steps only, or c(x) instead of c(y), would not.
  for (std::string m : {"pssmlt", "pssmlt-bdpt", "mmlt"}) {
    RenderSettings s = settingsFor(m, 21, 1024);
    s.bootstrapSamples = 1 << 16;  // the small light seen directly gives c a large variance here
    const JobPlan plan = planJob(cornell(), s);
    const PartialResult merged = runJob(plan);
    int powerful = 0;  // slots where the comparison could detect a 30% bias
    ASSERT_EQ(merged.stats.largeStepSums.size(), plan.norm.bootstrapB.size()) << m.c_str();
    uint64_t large = 0;
    for (size_t slot = 0; slot < plan.norm.bootstrapB.size(); ++slot) {
      const TargetSums& L = merged.stats.largeStepSums[slot];
      const BootstrapEstimate& boot = plan.norm.bootstrapB[slot];
      large += L.n;
      if (boot.n == 0 || boot.b == 0) {
        EXPECT_EQ(L.n, 0u) << m.c_str() << " slot " << slot << ": no chains, no large steps";
        continue;
      }
      const BEstimate l = pooledB({}, L), b{boot.b, boot.stdErr, boot.n};
      ASSERT_GT(L.n, 100u) << m.c_str() << " slot " << slot;
      const double se = std::hypot(l.stdErr, b.stdErr);
      EXPECT_LT(std::fabs(l.b - b.b), 5 * se) << m.c_str() << " slot " << slot << ": large steps " << l.b
                                               << " +- " << l.stdErr << ", bootstrap " << b.b << " +- " << b.stdErr;
      if (5 * se < 0.3 * b.b) ++powerful;
    }
    EXPECT_GE(powerful, m == "mmlt" ? 3 : 1) << m.c_str() << ": the comparison is too weak to fail";
    EXPECT_EQ(large, merged.stats.proposedPerKind[int(MutationType::Large)]) << m.c_str()
                                                                             << ": every large step is counted once";
  }
}

TEST(RefinedB, RaoBlackwellizedBSamplesRefineTheLengthsOfSeveralTechniques) {
  // --b-sample-every N (develop.h (D9)): every length of several techniques is refined by ceil(M / N) b
  // samples per chain instead of its large steps (length 1, one technique, keeps them), the plan keeps no
  // bootstrap estimate for those lengths, the samples' mean agrees with b_k from 65536 bootstrap candidates
  // (c, other numbers) within their combined error, their variance per sample is below c's (Rao-Blackwell),
  // and a chain gives the same bits twice.
  for (std::string m : {"mmlt", "rjmlt"}) {
    RenderSettings s = settingsFor(m, 21, 256);
    s.bootstrapSamples = 1 << 16;
    const JobPlan plain = planJob(cornell(), s);
    s.params["b-sample-every"] = "4";
    const JobPlan plan = planJob(cornell(), s);
    ASSERT_EQ(plan.norm.mutationsPerLength, plain.norm.mutationsPerLength) << m << ": the same bootstrap and chains";
    std::vector<uint64_t> expected(plan.norm.mutationsPerLength.size(), 0);
    for (const WorkUnit& u : plan.units) expected[size_t(u.pathLength)] += (u.mutations + 3) / 4;
    const PartialResult merged = runJob(plan);
    ASSERT_EQ(merged.stats.largeStepSums.size(), plan.norm.bootstrapB.size()) << m;
    int powerful = 0;
    for (size_t k = 1; k < plan.norm.mutationsPerLength.size(); ++k) {
      const TargetSums& L = merged.stats.largeStepSums[k];
      const BootstrapEstimate& boot = plain.norm.bootstrapB[k];
      if (plan.norm.mutationsPerLength[k] == 0) continue;
      if (k == 1) {  // one technique: the large steps, and the bootstrap's estimate
        EXPECT_EQ(plan.norm.bootstrapB[k], plain.norm.bootstrapB[k]) << m;
        EXPECT_EQ(L.n, merged.stats.proposedPerLengthKind[k * ChainStats::kKindStride + int(MutationType::Large)]) << m;
        continue;
      }
      EXPECT_EQ(plan.norm.bootstrapB[k].n, 0u) << m << " k " << k << ": b_k from the b samples alone";
      EXPECT_EQ(L.n, expected[k]) << m << " k " << k << ": ceil(M / 4) per chain";
      const BEstimate hat = pooledB({}, L);
      const double se = std::hypot(hat.stdErr, boot.stdErr);
      EXPECT_LT(std::fabs(hat.b - boot.b), 5 * se) << m << " k " << k << ": b samples " << hat.b << " +- "
                                                    << hat.stdErr << ", bootstrap " << boot.b << " +- " << boot.stdErr;
      if (5 * se < 0.3 * boot.b) ++powerful;
      const double n = double(L.n), varHat = (L.sumSq - n * hat.b * hat.b) / (n - 1);
      EXPECT_LT(varHat, boot.sampleVar) << m << " k " << k << ": Var c^ " << varHat << " vs Var c " << boot.sampleVar;
      std::printf("%s k=%zu: b samples %.5g +- %.2g (%llu), bootstrap %.5g +- %.2g; Var c^ / Var c = %.3f\n", m.c_str(),
                  k, hat.b, hat.stdErr, (unsigned long long)L.n, boot.b, boot.stdErr, varHat / boot.sampleVar);
    }
    EXPECT_GE(powerful, 2) << m << ": the comparison is too weak to fail";
    const ChainReport report = makeChainReport(plan, merged);
    EXPECT_EQ(report.bSampleEvery, 4u);
    EXPECT_EQ(makeChainReport(plain, PartialResult{}).bSampleEvery, 0u);
    EXPECT_NE(formatChainSummary(report, -1, -1, "").find("one fresh point per 4 mutations"), std::string::npos);
    ImageMetadata md;
    addChainMetadata(report, md);
    EXPECT_EQ(chainReportFromMetadata(md).bSampleEvery, 4u) << "the stride travels with the image";
    // Deterministic: a chain of length >= 2 run twice gives the same sums, bit for bit.
    for (const WorkUnit& u : plan.units)
      if (u.pathLength >= 2) {
        const PartialResult a = runWorkUnit(cornell(), plan, u), b = runWorkUnit(cornell(), plan, u);
        EXPECT_EQ(a.stats.largeStepSums, b.stats.largeStepSums) << m;
        break;
      }
  }
}

TEST(RefinedB, StandardErrorShrinksAsTheJobGrows) {
  // Same bootstrap, 64x the mutations: b's standard error falls below the bootstrap's and keeps falling as
  // the job grows, and the combination is never worse than either of its parts (develop.h (D5)).
  for (std::string m : {"pssmlt", "mmlt"}) {
    const JobPlan small = planJob(cornell(), settingsFor(m, 5, 16));
    const JobPlan big = planJob(cornell(), settingsFor(m, 5, 1024));
    EXPECT_EQ(small.norm.b, big.norm.b) << "one bootstrap for both";
    const ChainReport rs = makeChainReport(small, runJob(small));
    const PartialResult bigRun = runJob(big);
    const ChainReport rb = makeChainReport(big, bigRun);
    EXPECT_LT(rs.bStdErr, rs.bBootstrapStdErr) << m.c_str() << ": the large steps add information";
    if (m == "pssmlt") {
      EXPECT_LT(rb.bStdErr, 0.9 * rs.bStdErr) << m.c_str() << ": " << rb.bStdErr << " vs " << rs.bStdErr;
    } else {
      // mmlt allocates by allocationWeights (common/mlt/allocation.h): length 1, the light seen directly, gets a few
      // percent of the mutations and its b_1 (most of b's variance here) stays mostly the bootstrap's.
      // Every length with a sizeable share of the mutations must gain, and b as a whole.
      EXPECT_LT(rb.bStdErr, rs.bStdErr) << m.c_str();
      ASSERT_EQ(rb.lengths.size(), rs.lengths.size());
      for (size_t l = 0; l < rb.lengths.size(); ++l) {
        std::printf("k=%d: %.3g -> %.3g (%llu -> %llu mutations)\n", rb.lengths[l].k, rs.lengths[l].bkStdErr,
                    rb.lengths[l].bkStdErr, (unsigned long long)rs.lengths[l].mutations,
                    (unsigned long long)rb.lengths[l].mutations);
        if (rb.lengths[l].mutations >= rb.mutations / 10) {
          EXPECT_LT(rb.lengths[l].bkStdErr, 0.9 * rs.lengths[l].bkStdErr) << "length " << rb.lengths[l].k;
        }
      }
    }
    if (m == "pssmlt") {  // one length: compare with the large steps' own stated error (combineB: the larger
                          // of the bootstrap's model variance and their own spread)
      const TargetSums& large = bigRun.stats.largeStepSums.at(0);
      const double nL = double(large.n), bL = large.sum / nL;
      const double spread = (large.sumSq - nL * bL * bL) / (nL - 1) / nL;
      const double largeOnly = std::sqrt(std::max(big.norm.bootstrapB[0].sampleVar / nL, spread));
      EXPECT_EQ(large.n, rb.steps("large"));
      EXPECT_LE(rb.bStdErr, std::min(rb.bBootstrapStdErr, largeOnly));
    }
    EXPECT_EQ(rb.bSamples, big.norm.bootstrapSamplesInB + rb.steps("large"));
  }
}

TEST(RefinedB, ImageIsDevelopedWithTheRefinedB) {
  // Scaling every large-step sum by 2 doubles b_k (and nothing else), so every chain layer's
  // contribution doubles: the image minus its direct pass doubles exactly. (Expected values: Kelemen MIS's
  // large-step layers are developed with the bootstrap's b_k, (D7), MltChain1D.KelemenMisStaysRight...)
  RenderSettings s = settingsFor("mmlt", 9, 32);
  s.splatting = MltSplatting::ExpectedValue;
  const JobPlan plan = planJob(cornell(), s);
  PartialResult merged = runJob(plan);
  const std::vector<Color> before = developImage(plan, merged);
  JobPlan noBoot = plan;
  for (BootstrapEstimate& e : noBoot.norm.bootstrapB) e = {};  // b from the large steps alone
  const std::vector<Color> largeOnly = developImage(noBoot, merged);
  for (TargetSums& t : merged.stats.largeStepSums) {
    t.sum *= 2;
    t.sumSq *= 4;
    t.bulk *= 2;
    t.bulkSq *= 4;
    t.excessSq *= 4;
  }
  for (size_t slot = 0; slot < merged.stats.largeStepSums.size(); ++slot)  // and their strata (D6)
    if (merged.film.hasSplatLayer(bStrataLayer(slot)))
      for (RGBd& v : merged.film.splatLayer(bStrataLayer(slot))) {
        v.g *= 2;
        v.b *= 4;
      }
  const std::vector<Color> doubled = developImage(noBoot, merged);
  double a = 0, b = 0, c = 0;
  for (size_t i = 0; i < before.size(); ++i) {
    a += luminance(before[i]);
    b += luminance(largeOnly[i]);
    c += luminance(doubled[i]);
  }
  EXPECT_GT(a, 0);
  EXPECT_NEAR(c, 2 * b, 1e-4 * b);
  EXPECT_NE(a, b) << "the bootstrap's samples enter the pooled b";
}

TEST(RefinedB, LargeStepSumsMergeExactlyInAnyGrouping) {
  const JobPlan plan = planJob(cornell(), settingsFor("mmlt", 13, 64));
  std::vector<PartialResult> parts(plan.units.size());
  for (size_t i = 0; i < parts.size(); ++i) parts[i] = runWorkUnit(cornell(), plan, plan.units[i]);
  PartialResult sequential, grouped;
  for (const PartialResult& p : parts) sequential.add(p);
  for (size_t g = 0; g < parts.size(); g += 5) {
    PartialResult group;
    for (size_t i = g; i < std::min(parts.size(), g + 5); ++i) group.add(parts[i]);
    grouped.add(group);
  }
  ASSERT_EQ(sequential.stats.largeStepSums.size(), grouped.stats.largeStepSums.size());
  for (size_t l = 0; l < sequential.stats.largeStepSums.size(); ++l)
    EXPECT_TRUE(sequential.stats.largeStepSums[l] == grouped.stats.largeStepSums[l]) << "slot " << l;
}

TEST(RefinedB, EachPathLengthSplatsIntoItsOwnLayer) {
  const JobPlan plan = planJob(cornell(), settingsFor("mmlt", 17, 8));
  ASSERT_EQ(plan.settings.splatting, MltSplatting::KelemenMIS);
  const size_t slots = plan.norm.mutationsPerLength.size();
  for (const WorkUnit& u : plan.units) {
    PartialResult r = runWorkUnit(cornell(), plan, u);
    r.foldSplats();  // a chain unit's splats travel sparse (common/film/sparse_splats.h)
    const size_t chain = chainLayer(size_t(u.pathLength)), large = largeStepLayer(size_t(u.pathLength), slots);
    ASSERT_TRUE(r.film.hasSplatLayer(chain)) << "unit " << u.index;
    ASSERT_TRUE(r.film.hasSplatLayer(large)) << "unit " << u.index << ": Kelemen MIS's large steps (D7)";
    for (size_t l = 1; l < r.film.splatLayerCount(); ++l)  // its splats only (mmlt keeps no strata, (D6))
      EXPECT_EQ(r.film.hasSplatLayer(l), l == chain || l == large) << "unit " << u.index << " layer " << l;
  }
}

TEST(BootstrapSize, AutomaticSizeIsASmallShareOfTheJob) {
  RenderSettings s = settingsFor("mmlt", 1, 256);
  s.bootstrapSamples = 0;
  s.width = 256;
  s.height = 256;
  s.integrator.maxDepth = 30;
  const double M = 256.0 * 256 * 256;
  const size_t L = chainPathLengths(s).size();
  const uint64_t n = bootstrapPerLength(s);
  EXPECT_LE(double(n * L), kBootstrapShare * M);
  EXPECT_GT(double(n * L), 0.99 * kBootstrapShare * M);  // all of it, in whole randomization groups
  EXPECT_EQ(n % (4 * kCandidateGroups), 0u);
  s.mutationsPerPixel = 1;  // a tiny job still gets enough candidates to find its lengths
  EXPECT_EQ(bootstrapPerLength(s), kMinBootstrapPerLength);
  s.mutationsPerPixel = 1e6;
  EXPECT_EQ(bootstrapPerLength(s), kMaxBootstrapPerLength);
  s.bootstrapSamples = 777;  // explicit wins
  EXPECT_EQ(bootstrapPerLength(s), 777u);
  // The plan records the resolved size, so that it can be reproduced.
  RenderSettings auto16 = settingsFor("pssmlt", 1, 16);
  auto16.bootstrapSamples = 0;
  const JobPlan plan = planJob(cornell(), auto16);
  EXPECT_EQ(plan.settings.bootstrapSamples, int(kMinBootstrapPerLength));
  // It holds the cost of that many of the chains' mutations (bootstrap.h, chainMixCost): a quarter of
  // them to start with, doubled while the budget allows.
  const uint64_t n0 = kMinBootstrapPerLength / 4, got = plan.norm.bootstrapSamples;
  EXPECT_GE(got, n0);
  EXPECT_EQ(got % n0, 0u);
  EXPECT_EQ((got / n0) & (got / n0 - 1), 0u) << got << ": a quarter, doubled";
}

// The bootstrap's budget counts cost (bootstrap.h): on a real scene every candidate reports the numbers it
// drew, a longer path draws more of them, and the cost spent stays within the cost of N of the chains'
// mutations per length (the budget of its first round's mix).
TEST(BootstrapSize, CandidatesReportTheirWorkAndTheBudgetHoldsInCost) {
  RenderSettings s = settingsFor("mmlt", 3, 16);
  s.integrator.maxDepth = 8;
  s.bootstrapSamples = 2048;
  s.width = 16;
  s.height = 12;
  const ChainJobSpec* spec = findChainJobSpec("mmlt");
  ASSERT_TRUE(spec);
  const MarkovChainBootstrap boot = bootstrapMarkovChainJob(*spec, cornell(), s);
  const std::vector<LengthBootstrap>& L = boot.result.lengths;
  ASSERT_EQ(L.size(), 8u);
  for (const LengthBootstrap& lb : L) ASSERT_EQ(lb.work.size(), lb.c.size()) << "k = " << lb.pathLength;
  const double spent = bootstrapCost(L);
  // Length 1 (the light seen directly) draws the fewest numbers, the longest length the most.
  EXPECT_LT(candidateCost(L.front()), candidateCost(L.back()));
  for (const LengthBootstrap& lb : L) EXPECT_GE(candidateCost(lb), candidateCost(L.front())) << lb.pathLength;
  // Within the budget, measured as the doublings measure it: with the first round's (a quarter per length)
  // cost per candidate, which the full counts only refine. Allow for that refinement: 10%.
  const double budget = 2048.0 * double(L.size()) * chainMixCost(L);
  EXPECT_LE(spent, 1.1 * budget);
  EXPECT_GE(boot.result.candidates, L.size() * 2048 / 4);
}

// A bootstrap candidate of veach-mlt is a whole bdpt sample, 3-10 of its mutations: the count-sized
// bootstrap holds 1 / candidateCost of the candidates pssmlt-bdpt's holds at the same settings (the same share of
// the job's time; the results page measured veach-mlt's bootstrap at 13-25% of the job before this).
TEST(BootstrapSize, CandidatesAreSizedByTheirCostInMutations) {
  const ChainJobSpec* veach = findChainJobSpec("veach-mlt");
  const ChainJobSpec* pss = findChainJobSpec("pssmlt-bdpt");
  ASSERT_TRUE(veach && pss);
  RenderSettings s = settingsFor("pssmlt-bdpt", 1, 256);  // below kMaxBootstrapPerLength
  EXPECT_EQ(pss->candidateCost(s), 1.0);
  EXPECT_GT(veach->candidateCost(s), 1.0);
  RenderSettings deep = s;
  deep.integrator.maxDepth = 12;
  EXPECT_GT(veach->candidateCost(deep), veach->candidateCost(s));  // a bdpt sample grows faster with depth
  s.bootstrapSamples = 0;
  s.width = 256;
  s.height = 256;
  const uint64_t nPss = bootstrapPerLength(*pss, s);
  s.method = "veach-mlt";
  const uint64_t nVeach = bootstrapPerLength(*veach, s);
  EXPECT_LE(double(nVeach), kBootstrapShare * 256.0 * 256 * 256 / veach->candidateCost(s));
  EXPECT_NEAR(double(nVeach) * veach->candidateCost(s), double(nPss), 64 * veach->candidateCost(s));
}

// What a vague b's warning and the summary say depends on where b's samples came from: large steps (a
// method that has them: --large-step helps), other independent samples of the chains (veach-mlt), none.
TEST(BootstrapSize, VagueBWarningNamesTheRemedyOfTheMethod) {
  ChainReport r;
  r.b = 1;
  r.bStdErr = 2 * kMaxRelativeStdErrB;
  r.bootstrapSamples = r.bootstrapSamplesInB = 4096;
  r.bSamples = 100000;
  r.kinds = {{"bidir", 10, 5}, {"lens", 10, 5}};  // veach-mlt: no large steps
  EXPECT_NE(chainWarnings(r).find("refined as the chains run"), std::string::npos) << chainWarnings(r);
  EXPECT_EQ(chainWarnings(r).find("--large-step"), std::string::npos) << chainWarnings(r);
  EXPECT_NE(formatChainSummary(r, 1, 1).find("independent samples"), std::string::npos) << formatChainSummary(r, 1, 1);
  r.kinds = {{"large", 10, 5}, {"small", 10, 5}};
  EXPECT_NE(chainWarnings(r).find("--large-step"), std::string::npos) << chainWarnings(r);
  EXPECT_NE(formatChainSummary(r, 1, 1).find("large steps"), std::string::npos) << formatChainSummary(r, 1, 1);
  r.bSamples = r.bootstrapSamples;  // nothing from the chains
  EXPECT_NE(chainWarnings(r).find("--bootstrap"), std::string::npos) << chainWarnings(r);
  // Several lengths sized by their values: b holds the first round only, and the summary says so.
  EXPECT_EQ(formatChainSummary(r, 1, 1).find("drawn"), std::string::npos) << formatChainSummary(r, 1, 1);
  r.bootstrapSamplesInB = 1024;
  r.bSamples = 1024;
  EXPECT_NE(formatChainSummary(r, 1, 1).find("1024 bootstrap candidates (of 4096 drawn"), std::string::npos)
      << formatChainSummary(r, 1, 1);
  EXPECT_NE(chainWarnings(r).find("bootstrap's 1024 samples"), std::string::npos) << chainWarnings(r);
}

}  // namespace
}  // namespace mlt
