// veach-mlt's light-view pass (common/methods/veach/light_view.h): the paths E S* L rendered by camera
// rays and left out of the chains.
//  - Its samples: the chains' ranges tile [0, P sppLV) in unit order, every pixel gets exactly sppLV
//    samples, a chain cut short (a time budget's trial) takes a prefix of its range, and the develop scale
//    is P / (samples merged).
//  - What it integrates is exactly what bdpt leaves out with dropLightViews (the candidates' and b samples'
//    target): per sample, full bdpt minus bdpt without light views, paired on the same numbers, against
//    the pass's own camera rays, on the box with a glass and a mirror sphere (the light seen directly, in
//    the mirror sphere and through the glass one). Image mean and 4 x 4 tiles within kZ standard errors,
//    for all light views and for those through at least one specular vertex; a pass that stopped at the
//    first specular vertex (only the light seen directly) is told apart by the same comparison.
//  - The chains' space leaves light views out (f = 0) and keeps every other path.
//  - veach-mlt on a scene whose light is seen only directly (nothing else lit): the chains' b is 0, and
//    the plan falls back to chains that carry the light views, so the light is still in the image.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <vector>

#include "common/integrators/bdpt.h"
#include "common/integrators/evaluators.h"
#include "common/job/mlt_job.h"
#include "common/methods/registry.h"
#include "common/methods/veach/light_view.h"
#include "common/methods/veach/path.h"
#include "common/methods/veach/veach_chain.h"
#include "common/methods/veach/veach_job.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"
#include "tests/support/estimates.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

constexpr double kZ = 4.5;  // 17 comparisons each
constexpr int kSize = 16, kTiles = 4;

JobPlan syntheticPlan(int width, int height, const std::vector<uint64_t>& mutations) {
  JobPlan plan;
  plan.settings.width = width;
  plan.settings.height = height;
  plan.settings.seed = 11;
  for (size_t i = 0; i < mutations.size(); ++i) {
    WorkUnit u;
    u.index = uint32_t(i);
    u.mutations = mutations[i];
    if (u.mutations == 0) u.sampleEnd = 1;  // a direct-pass unit: carries no light views
    plan.units.push_back(u);
  }
  return plan;
}

TEST(VeachLightView, ChainsTileTheSamplesAndEveryPixelGetsSppOfThem) {
  const int W = 7, H = 5;
  const uint64_t P = W * H;
  const JobPlan plan = syntheticPlan(W, H, {1, 5, 1000, 3, 77, 2, 640, 0, 0});
  for (const uint32_t spp : {1u, 3u, 16u}) {
    const uint64_t N = P * spp;
    uint64_t next = 0;
    std::vector<uint32_t> all;
    for (const WorkUnit& u : plan.units) {
      const auto [first, last] = veach::lightViewRange(plan, u, spp);
      if (u.mutations == 0) {
        EXPECT_EQ(first, last) << "unit " << u.index;
        continue;
      }
      EXPECT_EQ(first, next) << "unit " << u.index << ", spp " << spp;
      EXPECT_LE(first, last);
      next = last;
      all.push_back(u.index);
    }
    EXPECT_EQ(next, N) << "spp " << spp;
    std::vector<uint32_t> hits(P, 0);
    for (uint64_t i = 0; i < N; ++i) ++hits[veach::lightViewPixel(i, P)];
    for (uint64_t p = 0; p < P; ++p) EXPECT_EQ(hits[p], spp) << "pixel " << p;
    EXPECT_DOUBLE_EQ(veach::lightViewScale(plan, all, spp), 1.0 / spp);
    // A preview of some chains: P over the samples they carry.
    const auto [f2, l2] = veach::lightViewRange(plan, plan.units[2], spp);
    const auto [f6, l6] = veach::lightViewRange(plan, plan.units[6], spp);
    EXPECT_DOUBLE_EQ(veach::lightViewScale(plan, {2, 6}, spp), double(P) / double((l2 - f2) + (l6 - f6)));
  }
  // A chain cut short (the throughput trial of a time budget) renders the start of its range.
  WorkUnit trial = plan.units[2];
  trial.mutations = 10;
  const auto [ff, fl] = veach::lightViewRange(plan, plan.units[2], 16);
  const auto [tf, tl] = veach::lightViewRange(plan, trial, 16);
  EXPECT_EQ(tf, ff);
  EXPECT_LT(tl, fl);
  EXPECT_GT(tl, tf);
  EXPECT_EQ(veach::lightViewSpp(0, 100), 0u);
  EXPECT_EQ(veach::lightViewSpp(0.25, 100), 25u);
  EXPECT_EQ(veach::lightViewSpp(0.25, 0.5), 1u);
}

// What bdpt leaves out with dropLightViews, sample by sample (same numbers for both), restricted to
// light views of at least minEdges edges (t - 1 >= minEdges).
test::ImageStats droppedByBdpt(const RenderScene& scene, int maxDepth, int minEdges, uint64_t n) {
  IntegratorSettings is;
  is.maxDepth = maxDepth;
  const BdptEvaluator full(scene, is), dropped(scene, is, true);
  const uint64_t P = kSize * kSize;
  return test::estimateImageFrom(
      [&](uint64_t i, PathContribution& out) {
        IndependentSource a(21, i), b(21, i);
        const Vec2 pixel{float(i % P % kSize), float(i % P / kSize)};
        PathContribution ca, cb;
        full.evaluate(a, &pixel, ca);
        dropped.evaluate(b, &pixel, cb);
        Color all, kept;
        for (const Splat& s : ca.splats)
          if (s.s == 0 && s.t - 1 >= minEdges) all += s.L;
        for (const Splat& s : cb.splats)
          if (s.s == 0 && s.t - 1 >= minEdges) kept += s.L;
        const Color L(all.r - kept.r, all.g - kept.g, all.b - kept.b);
        out.splats.push_back(Splat{ca.cameraRaster, L, 0, 2});
      },
      kSize, kSize, n, kTiles, kTiles, -1, 4 * P);
}

// The pass's camera rays, one per sample, pixel i mod P.
test::ImageStats lightViewPass(const veach::PathSpace& space, uint64_t n) {
  const uint64_t P = kSize * kSize;
  return test::estimateImageFrom(
      [&](uint64_t i, PathContribution& out) {
        Pcg32 rng(hashKeys(uint64_t(5), i), 1);
        const Vec2 j = rng.uniform2();
        const Vec2 p{float(i % P % kSize) + j.x, float(i % P / kSize) + j.y};
        out.splats.push_back(Splat{p, veach::lightViewRadiance(space, p, rng), 0, 2});
      },
      kSize, kSize, n, kTiles, kTiles, -1, 4 * P);
}

TEST(VeachLightView, PassIntegratesWhatBdptLeavesOut) {
  const auto scene = RenderScene::build(test::cornellBoxSpecular(kSize, kSize));
  const int depth = 5;
  const uint64_t n = 2048 * kSize * kSize;
  for (const int minEdges : {1, 2}) {
    const test::ImageStats ref = droppedByBdpt(*scene, depth, minEdges, n);
    const veach::PathSpace space(*scene, depth, minEdges, true);
    const test::ImageStats pass = lightViewPass(space, n);
    int where = 0;
    const double z = test::maxZ(pass, ref, &where);
    std::printf("light views of >= %d edges: pass %.5f +- %.5f, bdpt's %.5f +- %.5f, max z %.2f at %d\n", minEdges,
                pass.mean[0], pass.stdErr[0], ref.mean[0], ref.stdErr[0], z, where);
    EXPECT_GT(ref.mean[0], 10 * ref.stdErr[0]) << "the scene must have such light views";
    EXPECT_LT(z, kZ) << "min edges " << minEdges;
  }
  // The comparison can fail: the light seen directly only (one edge) against all light views.
  const test::ImageStats ref = droppedByBdpt(*scene, depth, 1, n);
  const veach::PathSpace directOnly(*scene, 1, 1, true);
  const double zWrong = test::maxZ(lightViewPass(directOnly, n), ref);
  std::printf("the light seen directly only: max z %.2f\n", zWrong);
  EXPECT_GT(zWrong, kZ);
}

TEST(VeachLightView, ChainsLeaveLightViewsOut) {
  const auto scene = RenderScene::build(test::cornellBoxSpecular(kSize, kSize));
  const veach::PathSpace with(*scene, 5), without(*scene, 5, 1, true);
  IntegratorSettings is;
  is.maxDepth = 5;
  int views = 0, others = 0;
  for (uint64_t i = 0; i < 20000 && (views < 20 || others < 20); ++i) {
    IndependentSource source = IndependentSource::candidate(3, i);
    const std::optional<veach::StartPath> sp = veach::startPathFromSample(with, is, source, 0.5);
    if (!sp) continue;
    const bool view = veach::PathSpace::isLightView(sp->path);
    EXPECT_FALSE(with.f(sp->path, nullptr).isBlack());
    EXPECT_EQ(without.f(sp->path, nullptr).isBlack(), view) << "candidate " << i;
    (view ? views : others)++;
  }
  EXPECT_GE(views, 20);
  EXPECT_GE(others, 20);
}

TEST(VeachLightView, ALightSeenOnlyDirectlyIsStillRendered) {
  // The diffuse box with every surface black: only the light seen directly carries light.
  SceneDesc d = test::smallCornellBox(kSize, kSize);
  for (BsdfDesc& b : d.bsdfs) b.reflectance = TextureDesc{Color(0.0f)};
  const auto scene = RenderScene::build(d);
  RenderSettings s;
  s.method = "veach-mlt";
  s.width = s.height = kSize;
  s.integrator.maxDepth = 5;
  s.mutationsPerPixel = 64;
  s.seed = 3;
  const JobPlan plan = planJob(*scene, s);
  EXPECT_EQ(plan.settings.params.at("veach-light-view"), "0");
  PartialResult merged;
  for (const WorkUnit& u : plan.units) merged.add(runWorkUnit(*scene, plan, u));
  double sum = 0;
  for (const Color& c : developImage(plan, merged)) sum += luminance(c);
  IntegratorSettings is;
  is.maxDepth = 5;
  const test::ImageStats ref = test::estimateImage(BdptEvaluator(*scene, is), kSize, kSize, 9, 1024 * kSize * kSize, 1, 1);
  std::printf("light seen directly only: veach-mlt mean %.5f, bdpt %.5f +- %.5f\n", sum / (kSize * kSize), ref.mean[0],
              ref.stdErr[0]);
  // Not black (the light is there), and as bright as bdpt within b's own error (13% from the bootstrap's
  // 4096 candidates, refined by the chains' b samples) and bdpt's.
  EXPECT_GT(ref.mean[0], 0);
  EXPECT_NEAR(sum / (kSize * kSize), ref.mean[0], 0.25 * ref.mean[0]);
}

}  // namespace
}  // namespace mlt
