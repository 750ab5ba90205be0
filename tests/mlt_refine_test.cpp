// b refined as the job runs (common/mlt/develop.h (D3), (D4)): the chains' large steps are independent
// uniform samples of the target, their sums merge exactly, the pooled b's standard error shrinks as the
// job grows, the bootstrap is sized to a small share of the job, and normalization happens only when
// the image is developed (one film layer per path length).
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "common/core/rng.h"
#include "common/job/mlt_job.h"
#include "common/job/render_job.h"
#include "common/mlt/chain_report.h"
#include "common/mlt/develop.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(16, 12));
  return *scene;
}

RenderSettings settingsFor(Method m, uint64_t seed, double mpp) {
  RenderSettings s;
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

TEST(RefinedB, LargeStepsSampleTheTargetLikeTheBootstrap) {
  // The large steps' mean of c per path length agrees with the bootstrap's b_k within their combined
  // standard error: a chain that counted accepted large steps only, or c(x) instead of c(y), would not.
  for (Method m : {Method::PSSMLT, Method::PSSMLT_BDPT, Method::MMLT}) {
    RenderSettings s = settingsFor(m, 21, 1024);
    s.bootstrapSamples = 1 << 16;  // the small light seen directly gives c a large variance here
    const JobPlan plan = planJob(cornell(), s);
    const PartialResult merged = runJob(plan);
    int powerful = 0;  // slots where the comparison could detect a 30% bias
    ASSERT_EQ(merged.stats.largeStepSums.size(), plan.norm.bootstrapSums.size()) << methodName(m);
    uint64_t large = 0;
    for (size_t slot = 0; slot < plan.norm.bootstrapSums.size(); ++slot) {
      const TargetSums& L = merged.stats.largeStepSums[slot];
      const TargetSums& B = plan.norm.bootstrapSums[slot];
      large += L.n;
      if (B.n == 0 || B.sum == 0) {
        EXPECT_EQ(L.n, 0u) << methodName(m) << " slot " << slot << ": no chains, no large steps";
        continue;
      }
      const BEstimate l = pooledB({}, L), b = pooledB(B, {});
      ASSERT_GT(L.n, 100u) << methodName(m) << " slot " << slot;
      const double se = std::hypot(l.stdErr, b.stdErr);
      EXPECT_LT(std::fabs(l.b - b.b), 5 * se) << methodName(m) << " slot " << slot << ": large steps " << l.b
                                               << " +- " << l.stdErr << ", bootstrap " << b.b << " +- " << b.stdErr;
      if (5 * se < 0.3 * b.b) ++powerful;
    }
    EXPECT_GE(powerful, m == Method::MMLT ? 3 : 1) << methodName(m) << ": the comparison is too weak to fail";
    EXPECT_EQ(large, merged.stats.largeProposed) << methodName(m) << ": every large step is counted once";
  }
}

TEST(RefinedB, StandardErrorShrinksAsTheJobGrows) {
  // Same bootstrap, 64x the mutations: b's standard error falls with the square root of the samples it is
  // pooled from (bootstrap + large steps), here by 2x or more.
  for (Method m : {Method::PSSMLT, Method::MMLT}) {
    const JobPlan small = planJob(cornell(), settingsFor(m, 5, 16));
    const JobPlan big = planJob(cornell(), settingsFor(m, 5, 1024));
    EXPECT_EQ(small.norm.b, big.norm.b) << "one bootstrap for both";
    const ChainReport rs = makeChainReport(small, runJob(small));
    const ChainReport rb = makeChainReport(big, runJob(big));
    EXPECT_LT(rs.bStdErr, rs.bBootstrapStdErr) << methodName(m) << ": the large steps add information";
    const double predicted = std::sqrt(double(rs.bSamples) / double(rb.bSamples));
    ASSERT_LT(predicted, 0.5) << methodName(m);
    EXPECT_LT(rb.bStdErr, 1.3 * predicted * rs.bStdErr) << methodName(m) << ": " << rb.bStdErr << " vs " << rs.bStdErr;
    EXPECT_EQ(rb.bSamples, big.norm.bootstrapSamples + rb.largeSteps);
  }
}

TEST(RefinedB, ImageIsDevelopedWithTheRefinedB) {
  // Scaling every large-step sum by 2 doubles b_k (and nothing else), so every chain layer's
  // contribution doubles: the image minus its direct pass doubles exactly.
  RenderSettings s = settingsFor(Method::MMLT, 9, 32);
  const JobPlan plan = planJob(cornell(), s);
  PartialResult merged = runJob(plan);
  const std::vector<Color> before = developImage(plan, merged);
  JobPlan noBoot = plan;
  for (TargetSums& t : noBoot.norm.bootstrapSums) t = {};  // b from the large steps alone
  const std::vector<Color> largeOnly = developImage(noBoot, merged);
  for (TargetSums& t : merged.stats.largeStepSums) {
    t.sum *= 2;
    t.sumSq *= 4;
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
  const JobPlan plan = planJob(cornell(), settingsFor(Method::MMLT, 13, 64));
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
  const JobPlan plan = planJob(cornell(), settingsFor(Method::MMLT, 17, 8));
  for (const WorkUnit& u : plan.units) {
    const PartialResult r = runWorkUnit(cornell(), plan, u);
    for (size_t l = 1; l < r.film.splatLayerCount(); ++l)
      EXPECT_EQ(r.film.hasSplatLayer(l), l == chainLayer(size_t(u.pathLength))) << "unit " << u.index << " layer " << l;
  }
}

TEST(BootstrapSize, AutomaticSizeIsASmallShareOfTheJob) {
  RenderSettings s = settingsFor(Method::MMLT, 1, 256);
  s.bootstrapSamples = 0;
  s.width = 256;
  s.height = 256;
  s.integrator.maxDepth = 30;
  const double M = 256.0 * 256 * 256;
  const size_t L = chainPathLengths(s).size();
  const uint64_t n = bootstrapPerLength(s);
  EXPECT_LE(double(n * L), kBootstrapShare * M);
  EXPECT_GT(double(n * L), 0.5 * kBootstrapShare * M);  // the largest power of two that fits
  EXPECT_EQ(n & (n - 1), 0u);
  s.mutationsPerPixel = 1;  // a tiny job still gets enough candidates to find its lengths
  EXPECT_EQ(bootstrapPerLength(s), kMinBootstrapPerLength);
  s.mutationsPerPixel = 1e6;
  EXPECT_EQ(bootstrapPerLength(s), kMaxBootstrapPerLength);
  s.bootstrapSamples = 777;  // explicit wins
  EXPECT_EQ(bootstrapPerLength(s), 777u);
  // The plan records the resolved size, so that it can be reproduced.
  RenderSettings auto16 = settingsFor(Method::PSSMLT, 1, 16);
  auto16.bootstrapSamples = 0;
  const JobPlan plan = planJob(cornell(), auto16);
  EXPECT_EQ(plan.settings.bootstrapSamples, int(kMinBootstrapPerLength));
  EXPECT_EQ(plan.norm.bootstrapSamples, kMinBootstrapPerLength);
}

}  // namespace
}  // namespace mlt
