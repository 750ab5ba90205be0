// Unbiasedness of the Markov chain methods through the job API (plan -> units -> merge -> develop):
// pssmlt, pssmlt-bdpt and mmlt (plus Kelemen's MIS splatting and separateDirect) against bdpt on a small
// Cornell box (image mean and 3x3 tile means, luminance), and against the analytic radiance of the
// furnace sphere.
//
// Tolerance: each MLT configuration is rendered with R independent job seeds (bootstrap included, so
// the spread contains b's error); its standard error is the spread of the R runs / sqrt(R). bdpt's
// comes from its batch spread. The largest z = |difference| / combined standard error over the 10
// entries must stay below kZ: with t(R-1 = 15 dof) tails, P(|t| > 5) ~ 1.6e-4 per entry, ~1% over
// the ~60 entries in this file.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "common/integrators/evaluators.h"
#include "common/methods/registry.h"
#include "common/render/render_scene.h"
#include "tests/support/estimates.h"
#include "tests/support/mlt_stats.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

constexpr int kRuns = 16;
constexpr double kZ = 5.0;
constexpr int kW = 24, kH = 18, kTiles = 3;

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(kW, kH));
  return *scene;
}

test::ImageStats mltStats(const RenderScene& scene, const RenderSettings& s, int w, int h) {
  return test::markovChainStats(scene, s, w, h, kRuns, kTiles);
}

const test::ImageStats& bdptReference() {
  static const test::ImageStats ref = [] {
    IntegratorSettings is;
    is.maxDepth = 5;
    const BdptEvaluator bdpt(cornell(), is);
    return test::estimateImage(bdpt, kW, kH, 4242, uint64_t(kW) * kH * 2048, kTiles, kTiles);
  }();
  return ref;
}

RenderSettings cornellSettings(std::string m) {
  RenderSettings s;
  s.directLight = DirectLight::Chains;  // chains over every length (the automatic choice: direct_light_rule_test)
  s.method = m;
  s.integrator.maxDepth = 5;
  s.mutationsPerPixel = 32;
  s.bootstrapSamples = 80000;  // b's error (~2% per run here: the visible light) dominates the image mean
  s.chains = 16;
  return s;
}

void expectAgreesWithBdpt(const RenderSettings& s, const char* label) {
  const test::ImageStats mlt = mltStats(cornell(), s, kW, kH);
  const test::ImageStats& ref = bdptReference();
  int where = 0;
  const double z = test::maxZ(mlt, ref, &where);
  EXPECT_LT(z, kZ) << label << ": entry " << where << " (0 = image mean) mlt " << mlt.mean[where] << " +- "
                   << mlt.stdErr[where] << " vs bdpt " << ref.mean[where] << " +- " << ref.stdErr[where];
  std::printf("%s: image mean %.5f +- %.5f, bdpt %.5f +- %.5f, max z %.2f\n", label, mlt.mean[0], mlt.stdErr[0],
              ref.mean[0], ref.stdErr[0], z);
  // The comparison must be able to fail: a 6% brightness error would exceed kZ on the image mean.
  EXPECT_LT(kZ * std::hypot(mlt.stdErr[0], ref.stdErr[0]), 0.06 * ref.mean[0]) << label << ": test too weak";
}

TEST(MltRender, PssmltAgreesWithBdpt) { expectAgreesWithBdpt(cornellSettings("pssmlt"), "pssmlt"); }

TEST(MltRender, PssmltBdptAgreesWithBdpt) {
  expectAgreesWithBdpt(cornellSettings("pssmlt-bdpt"), "pssmlt-bdpt");
}

TEST(MltRender, MmltAgreesWithBdpt) { expectAgreesWithBdpt(cornellSettings("mmlt"), "mmlt"); }

TEST(MltRender, KelemenMisSplattingAgreesWithBdpt) {
  RenderSettings s = cornellSettings("pssmlt-bdpt");
  s.splatting = MltSplatting::KelemenMIS;
  s.kernel = MutationKernel::Gaussian;
  s.largeStepProb = 0.5f;
  expectAgreesWithBdpt(s, "pssmlt-bdpt, Kelemen MIS, Gaussian kernel");
}

// Kelemen MIS is the default; expected values stay an option (and veach-mlt's only scheme).
TEST(MltRender, ExpectedValueSplattingAgreesWithBdpt) {
  RenderSettings s = cornellSettings("mmlt");
  s.splatting = MltSplatting::ExpectedValue;
  expectAgreesWithBdpt(s, "mmlt, expected values");
}

TEST(MltRender, SeparateDirectAgreesWithBdpt) {
  RenderSettings s = cornellSettings("mmlt");
  s.directLight = DirectLight::Separate;
  s.spp = 64;  // the direct pass (same seeds in every run would share its noise otherwise)
  expectAgreesWithBdpt(s, "mmlt, direct by a pt pass");
}

// The lights seen directly by a pt pass at stratified pixel points, the chains from length 2 on
// (DirectLight::Emission): the two together are the image bdpt renders.
TEST(MltRender, EmissionPassAgreesWithBdpt) {
  for (const char* m : {"mmlt", "rjmlt", "pssmlt-bdpt"}) {
    RenderSettings s = cornellSettings(m);
    s.directLight = DirectLight::Emission;
    s.spp = 16;
    expectAgreesWithBdpt(s, (std::string(m) + ", the lights seen directly by a pt pass").c_str());
  }
}

TEST(MltRender, FurnaceSphereMatchesAnalyticRadiance) {
  const float Le = 1.0f, rho = 0.5f;
  const int maxDepth = 4;
  const auto scene = RenderScene::build(test::furnaceSphere(Le, rho, 8, 8, 8));
  const double expected = luminance(Color(float(test::furnaceRadiance(Le, rho, maxDepth))));
  for (std::string m : {"pssmlt", "pssmlt-bdpt", "mmlt"}) {
    RenderSettings s;
    s.method = m;
    s.integrator.maxDepth = maxDepth;
    s.mutationsPerPixel = 256;
    s.bootstrapSamples = 5000;
    s.chains = 8;
    const test::ImageStats st = test::markovChainStats(*scene, s, 8, 8, kRuns, /*tiles=*/1);  // image mean only
    EXPECT_LT(std::fabs(st.mean[0] - expected), kZ * st.stdErr[0] + 1e-4 * expected)
        << m.c_str() << ": " << st.mean[0] << " +- " << st.stdErr[0] << " vs analytic " << expected;
  }
}

TEST(MltRender, MmltWithUnlimitedDepthMatchesTheInfiniteSeries) {
  // Le / (1 - rho): every path length carries light. The bootstrap adds blocks of lengths until one
  // carries less than kNegligibleLengthShare of b; here 0.5^k, so lengths 1..24 (the rest: ~6e-8 of b).
  const float Le = 1.0f, rho = 0.5f;
  const auto scene = RenderScene::build(test::furnaceSphere(Le, rho, 8, 8, 8));
  RenderSettings s;
  s.directLight = DirectLight::Chains;  // the bootstrap's blocks of lengths from 1 on
  s.method = "mmlt";
  s.integrator.maxDepth = -1;
  s.mutationsPerPixel = 768;  // at 512 (expected values' size) Kelemen MIS's error was just above the resolution below
  s.bootstrapSamples = 5000;
  s.chains = 24;
  const JobPlan plan = planJob(*scene, s);
  EXPECT_EQ(plan.norm.mutationsPerLength.size(), size_t(25)) << "lengths 1..24";
  EXPECT_GT(plan.norm.bk[16], 0.0) << "length 16 carries light";
  const double expected = luminance(Color(float(test::furnaceRadiance(Le, rho, -1))));
  const test::ImageStats st = test::markovChainStats(*scene, s, 8, 8, kRuns, /*tiles=*/1);
  EXPECT_LT(std::fabs(st.mean[0] - expected), kZ * st.stdErr[0] + 1e-4 * expected)
      << st.mean[0] << " +- " << st.stdErr[0] << " vs analytic " << expected;
  // The test can fail: truncating at the scene's depth 8 would be 0.4% dark, more than its resolution.
  EXPECT_LT(kZ * st.stdErr[0], expected - test::furnaceRadiance(Le, rho, 8));
}

}  // namespace
}  // namespace mlt
