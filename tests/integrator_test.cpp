// pt, lt and bdpt against analytic values and against each other, with tolerances from measured standard
// errors (|difference| < kZ standard errors; samples independent, fixed seeds).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "common/integrators/evaluators.h"
#include "common/render/render_scene.h"
#include "tests/support/estimates.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

using test::ImageStats;

// 5 sigma: with ~40 comparisons of ~17 entries each the chance of a false alarm is ~0.04% per run, and the
// seeds are fixed anyway.
constexpr double kZ = 5.0;

ImageStats run(const RenderScene& scene, std::string m, IntegratorSettings is, uint64_t seed, uint64_t n, int channel = -1,
               int tiles = 4) {
  const auto ev = makeEvaluator(scene, m, is);
  return test::estimateImage(*ev, scene.camera().width(), scene.camera().height(), seed, n, tiles, tiles, channel);
}

IntegratorSettings settings(int maxDepth, int rrDepth = 5, MisHeuristic h = MisHeuristic::Power) {
  IntegratorSettings s;
  s.maxDepth = maxDepth;
  s.rrDepth = rrDepth;
  s.heuristic = h;
  return s;
}

// ---- Analytic: the furnace sphere -----------------------------------------------------------------
TEST(Integrators, FurnaceSphereMatchesAnalyticRadiance) {
  const float Le = 1.0f, rho = 0.6f;
  const auto scene = RenderScene::build(test::furnaceSphere(Le, rho, 12));
  for (std::string m : {"pt", "lt", "bdpt"}) {
    for (int maxDepth : {1, 2, 3, 5, -1}) {
      // lt splats only the fraction of light-path vertices inside the frustum: more samples.
      const uint64_t n = m == "bdpt" ? 20000 : (m == "lt" ? 300000 : 40000);
      const ImageStats st = run(*scene, m, settings(maxDepth, 3), 7 + maxDepth, n, /*channel=*/0, 1);
      const double expected = test::furnaceRadiance(Le, rho, maxDepth);
      SCOPED_TRACE(std::string(m.c_str()) + " maxDepth " + std::to_string(maxDepth));
      EXPECT_LT(test::zImage(st, expected), kZ) << "estimate " << st.mean[0] << " +- " << st.stdErr[0]
                                                << ", expected " << expected;
      // Power: the error bar must resolve one more bounce (rho^maxDepth Le), or the test could not fail.
      if (maxDepth > 0) EXPECT_LT(kZ * st.stdErr[0], 0.5 * Le * std::pow(rho, maxDepth));
    }
  }
}

// ---- Agreement on the Cornell box ------------------------------------------------------------------
void expectAgree(const ImageStats& a, const ImageStats& b, const char* what) {
  int where = -1;
  std::printf("%-22s image mean %.5f +- %.5f vs %.5f +- %.5f, max z over tiles %.2f\n", what, a.mean[0],
              a.stdErr[0], b.mean[0], b.stdErr[0], test::maxZ(a, b));
  const double z = test::maxZ(a, b, &where);
  EXPECT_LT(z, kZ) << what << ": entry " << where << " (0 = image mean, else tile) " << a.mean[where] << " +- "
                   << a.stdErr[where] << " vs " << b.mean[where] << " +- " << b.stdErr[where];
}

TEST(Integrators, CornellBoxPtLtBdptAgree) {
  const auto scene = RenderScene::build(test::smallCornellBox(32, 24));
  const IntegratorSettings is = settings(5);
  const ImageStats pt = run(*scene, "pt", is, 1, 1000000);
  const ImageStats lt = run(*scene, "lt", is, 2, 1000000);
  const ImageStats bd = run(*scene, "bdpt", is, 3, 400000);
  expectAgree(pt, lt, "pt vs lt");
  expectAgree(pt, bd, "pt vs bdpt");
  expectAgree(lt, bd, "lt vs bdpt");
  EXPECT_GT(pt.mean[0], 0.05);
  // Power: the comparisons resolve a 3% brightness error in the image mean.
  EXPECT_LT(kZ * std::hypot(lt.stdErr[0], bd.stdErr[0]), 0.03 * lt.mean[0]);
  EXPECT_LT(kZ * std::hypot(lt.stdErr[0], pt.stdErr[0]), 0.03 * lt.mean[0]);
}

TEST(Integrators, BdptBalanceAndPowerHeuristicsAgree) {
  const auto scene = RenderScene::build(test::smallCornellBox(32, 24));
  const ImageStats p = run(*scene, "bdpt", settings(4, 5, MisHeuristic::Power), 11, 200000);
  const ImageStats b = run(*scene, "bdpt", settings(4, 5, MisHeuristic::Balance), 12, 200000);
  expectAgree(p, b, "power vs balance");
}

TEST(Integrators, PointAndSpotLightsAgree) {
  const auto scene = RenderScene::build(test::cornellBoxPointSpot(32, 24));
  const IntegratorSettings is = settings(4);
  const ImageStats pt = run(*scene, "pt", is, 21, 600000);
  const ImageStats lt = run(*scene, "lt", is, 22, 600000);
  const ImageStats bd = run(*scene, "bdpt", is, 23, 300000);
  expectAgree(pt, lt, "pt vs lt");
  expectAgree(pt, bd, "pt vs bdpt");
}

TEST(Integrators, SpecularSceneAgrees) {
  // Glass and mirror spheres: lt cannot see specular surfaces through a pinhole, so pt vs bdpt only.
  const auto scene = RenderScene::build(test::cornellBoxSpecular(32, 24));
  const IntegratorSettings is = settings(6);
  const ImageStats pt = run(*scene, "pt", is, 31, 800000);
  const ImageStats bd = run(*scene, "bdpt", is, 32, 300000);
  expectAgree(pt, bd, "pt vs bdpt");
}

// ---- Russian roulette does not bias ----------------------------------------------------------------
TEST(Integrators, RussianRouletteIsUnbiased) {
  const auto scene = RenderScene::build(test::smallCornellBox(32, 24));
  for (std::string m : {"pt", "lt", "bdpt"}) {
    SCOPED_TRACE(m.c_str());
    const uint64_t n = m == "bdpt" ? 150000 : 300000;
    const ImageStats early = run(*scene, m, settings(8, 1), 41, n);
    const ImageStats late = run(*scene, m, settings(8, 100), 42, n);
    expectAgree(early, late, "rrDepth 1 vs 100");
  }
}

TEST(Integrators, MaxDepthOneSeesOnlyEmitters) {
  // maxDepth = 1: only the light itself (tile means elsewhere are zero).
  const auto scene = RenderScene::build(test::smallCornellBox(32, 24));
  for (std::string m : {"pt", "lt", "bdpt"}) {
    const ImageStats st = run(*scene, m, settings(1), 51, 20000);
    // The light occupies only top-row tiles; bottom rows must be exactly zero.
    for (int k = 1 + 2 * 4; k < st.size(); ++k) EXPECT_EQ(st.mean[k], 0.0) << m.c_str() << " tile " << k;
    EXPECT_GT(st.mean[0], 0.0) << m.c_str();
  }
}

TEST(Integrators, FactoryRejectsMarkovChainMethods) {
  const auto scene = RenderScene::build(test::smallCornellBox(8, 8));
  EXPECT_THROW(makeEvaluator(*scene, "pssmlt", IntegratorSettings{}), std::invalid_argument);
  EXPECT_THROW(makeEvaluator(*scene, "mmlt", IntegratorSettings{}), std::invalid_argument);
  EXPECT_NO_THROW(makeEvaluator(*scene, "bdpt", IntegratorSettings{}));
}

}  // namespace
}  // namespace mlt
