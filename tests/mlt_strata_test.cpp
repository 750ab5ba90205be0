// b's large steps post-stratified by film position (common/mlt/strata.h, develop.h (D6)): the quadtree
// estimate is unbiased (also where most pixels hold no sample), removes the variance between pixels, and
// its stated variance matches its spread; a chain job keeps the strata layer and develops with it.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "common/core/rng.h"
#include "common/job/mlt_job.h"
#include "common/methods/chain_report.h"
#include "common/methods/registry.h"
#include "common/mlt/develop.h"
#include "common/mlt/strata.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

// A target whose mean depends strongly on the pixel: a bright block (about 5% of a 24x20 film, value 40)
// on a dim background (1), plus exponential noise of mean 1 within every pixel.
constexpr int kW = 24, kH = 20;
double pixelMean(size_t pixel) {
  const int x = int(pixel % kW), y = int(pixel / kW);
  return (x >= 3 && x < 7 && y >= 12 && y < 18) ? 40.0 : 1.0;
}
double trueMean() {
  double s = 0;
  for (size_t j = 0; j < size_t(kW) * kH; ++j) s += pixelMean(j);
  return s / double(kW * kH);
}

struct Trial {
  StratifiedMean strat;
  double plain = 0;
};
Trial drawTrial(Pcg32& rng, uint64_t n) {
  std::vector<RGBd> layer(size_t(kW) * kH);
  double sum = 0;
  for (uint64_t i = 0; i < n; ++i) {
    const size_t j = strataPixel(rng.uniform(), rng.uniform(), kW, kH);
    const double m = pixelMean(j) - 1 - std::log(1 - rng.uniformDouble());
    layer[j] += strataSample(m);
    sum += m;
  }
  return {postStratifiedMean(layer, kW, kH), sum / double(n)};
}

struct Moments {
  double mean = 0, var = 0, statedVar = 0;  // the stratified estimate over trials
  double plainVar = 0;                      // the plain mean's variance over the same trials
};
Moments runTrials(uint64_t n, int trials, uint64_t seed) {
  Pcg32 rng(seed, 7);
  std::vector<double> strat, plain;
  double stated = 0;
  for (int t = 0; t < trials; ++t) {
    const Trial tr = drawTrial(rng, n);
    EXPECT_TRUE(tr.strat.valid);
    EXPECT_EQ(tr.strat.n, n);
    strat.push_back(tr.strat.mean);
    plain.push_back(tr.plain);
    stated += tr.strat.var / trials;
  }
  Moments m;
  for (double v : strat) m.mean += v / trials;
  for (double v : strat) m.var += (v - m.mean) * (v - m.mean) / (trials - 1);
  m.statedVar = stated;
  double pm = 0, pv = 0;
  for (double v : plain) pm += v / trials;
  for (double v : plain) pv += (v - pm) * (v - pm) / (trials - 1);
  std::printf("n = %llu: stratified %.5f (sd %.4f, stated %.4f), plain %.5f (sd %.4f), true %.5f\n",
              (unsigned long long)n, m.mean, std::sqrt(m.var), std::sqrt(m.statedVar), pm, std::sqrt(pv), trueMean());
  m.plainVar = pv;
  return m;
}

TEST(BStrata, StratifiedMeanIsUnbiasedAndDropsTheVarianceBetweenPixels) {
  const int trials = 1000;
  const Moments m = runTrials(20 * kW * kH, trials, 3);
  EXPECT_NEAR(m.mean, trueMean(), 4 * std::sqrt(m.var / trials));
  // Within a pixel the variance is 1 (the noise); between pixels, about 72 (the bright block).
  EXPECT_LT(m.var, m.plainVar / 20) << "the variance between pixels is gone";
  // The stated variance (D6) matches the spread over trials (chi-square with 999 dof: within 15%).
  EXPECT_NEAR(m.statedVar / m.var, 1.0, 0.15);
}

TEST(BStrata, SparseSamplesCollapseStrataAndStayUnbiased) {
  // Half a sample per pixel: most pixels hold fewer than 2 samples and the quadtree pools them; the
  // choice depends on counts only, so the mean stays right, and it is still better than pooling all.
  const int trials = 3000;
  const Moments m = runTrials(kW * kH / 2, trials, 5);
  EXPECT_NEAR(m.mean, trueMean(), 4 * std::sqrt(m.var / trials));
  EXPECT_LT(m.var, m.plainVar);
  EXPECT_NEAR(m.statedVar / m.var, 1.0, 0.25);
}

TEST(BStrata, TooFewSamplesGiveNoEstimate) {
  std::vector<RGBd> layer(size_t(kW) * kH);
  EXPECT_FALSE(postStratifiedMean(layer, kW, kH).valid);
  layer[5] += strataSample(2.0);
  EXPECT_FALSE(postStratifiedMean(layer, kW, kH).valid) << "one sample has no variance";
  layer[300] += strataSample(4.0);
  const StratifiedMean two = postStratifiedMean(layer, kW, kH);
  ASSERT_TRUE(two.valid);
  EXPECT_DOUBLE_EQ(two.mean, 3.0);  // pooled at the root: the plain mean
  EXPECT_EQ(two.strata, 1u);
  EXPECT_THROW(postStratifiedMean(layer, kW + 1, kH), std::invalid_argument);
}

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(16, 12));
  return *scene;
}

TEST(BStrata, ChainUnitsKeepTheirLargeStepsPerPixelAndBIsDevelopedWithThem) {
  // One-length methods keep strata; mmlt and rjmlt (chains per length) do not (mlt_job_run.cpp, runMarkovChain).
  for (std::string method : {"pssmlt-bdpt", "pssmlt", "mmlt", "rjmlt"}) {
    const bool stratified = method == "pssmlt-bdpt" || method == "pssmlt";
    RenderSettings s;
    s.directLight = DirectLight::Chains;  // chains over every length (the automatic choice: direct_light_rule_test)
    s.method = method;
    s.seed = 23;
    s.integrator.maxDepth = 4;
    s.mutationsPerPixel = 512;
    s.bootstrapSamples = 4096;
    s.chains = 16;
    const JobPlan plan = planJob(cornell(), s);
    std::vector<PartialResult> parts(plan.units.size());
    tbb::parallel_for(size_t(0), plan.units.size(), [&](size_t i) { parts[i] = runWorkUnit(cornell(), plan, plan.units[i]); });
    PartialResult merged;
    for (const PartialResult& p : parts) merged.add(p);
    merged.foldSplats();
    // Every large step is in its slot's strata layer, once.
    for (size_t slot = 0; slot < merged.stats.largeStepSums.size(); ++slot) {
      const TargetSums& L = merged.stats.largeStepSums[slot];
      if (L.n == 0) continue;
      ASSERT_EQ(merged.film.hasSplatLayer(bStrataLayer(slot)), stratified) << method << " slot " << slot;
      if (!stratified) continue;
      double n = 0, bulk = 0;
      for (const RGBd& v : merged.film.splatLayer(bStrataLayer(slot))) {
        n += v.r;
        bulk += v.g;
      }
      EXPECT_EQ(n, double(L.n)) << method << " slot " << slot;
      EXPECT_NEAR(bulk, L.bulk, 1e-6 * L.bulk + 1e-9) << method << " slot " << slot;
    }
    // b developed with the strata: a different estimate from the same samples, agreeing with the plain one,
    // with a smaller stated error (every large step in one layer, several per pixel; this box's light is in
    // view). Without strata the film changes nothing.
    const RefinedB plain = refinedB(plan.norm, merged.stats), strat = refinedB(plan.norm, merged.stats, &merged.film);
    std::printf("%s: b %.5f +- %.5f plain, %.5f +- %.5f post-stratified\n", method.c_str(), plain.total.b,
                plain.total.stdErr, strat.total.b, strat.total.stdErr);
    if (stratified) {
      EXPECT_NE(plain.total.b, strat.total.b) << method;
      EXPECT_LT(strat.total.stdErr, 0.8 * plain.total.stdErr) << method;
      EXPECT_LT(std::fabs(strat.total.b - plain.total.b), 3 * plain.total.stdErr) << method;
    } else {
      EXPECT_EQ(plain.total.b, strat.total.b) << method;
    }
    EXPECT_EQ(makeChainReport(plan, merged).b, strat.total.b) << method << ": the report states b as developed";
  }
}

}  // namespace
}  // namespace mlt
