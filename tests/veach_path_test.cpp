// Veach's path state (common/methods/veach/path.h): the measurement contribution f(x) and the local
// densities are the ones bdpt integrates with. For paths built by bdpt's own subpaths (no roulette), the
// unweighted contribution of strategy (s, t) must equal
//     C(s, t) = f(x) / (prod_{i<s} lightStep(x, i) * lensDensity * prod_{i>=s} eyeStep(x, i)),
// which checks f (Le, G, the shading-normal form of the BSDF factors, We, the canonical measure at
// specular vertices) and both sides' densities at once, on specular chains traced from either side
// (glass and mirror spheres with shading normals): a light-traced chain's density times
// lightChainToCanonical (etendue conversion) must give the same C. Tolerances: 1e-3 without specular vertices, 3e-2 with (see the
// comment at the comparison). The start path of a chain replays the bootstrap's c exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "common/integrators/bdpt.h"
#include "common/methods/veach/path.h"
#include "common/methods/veach/veach_chain.h"
#include "common/integrators/evaluators.h"
#include "common/mlt/target.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

using veach::Path;
using veach::PathSpace;

struct Agreement {
  int compared = 0, agreed = 0, withSpecular = 0, lightChains = 0, deltaLight = 0, deltaLightChains = 0;
  double worst = 0;
};

Agreement compareStrategies(const RenderScene& scene, int maxDepth, uint64_t seed, int samples) {
  const PathSpace space(scene, maxDepth);
  Agreement a;
  BdptWorkspace ws;
  ws.reserve(maxDepth + 1, maxDepth);
  for (int n = 0; n < samples; ++n) {
    IndependentSource source(seed, uint64_t(n));
    Vec2 raster;
    const int nc = generateCameraSubpath(scene, source, nullptr, maxDepth + 1, -1, ws.camera.data(), &raster);
    const int nl = generateLightSubpath(scene, source, maxDepth, -1, ws.light.data());
    for (int t = 2; t <= nc; ++t) {
      for (int s = 0; s <= nl; ++s) {
        if (s + t - 1 > maxDepth || s + t < 2) continue;
        Vertex sampled;
        Vec2 pr = raster;
        const Color C = connectBdpt(scene, source, ws.light.data(), s, ws.camera.data(), t, &sampled, &pr);
        if (C.isBlack()) continue;
        // s = 1 resamples the light by NEE, whose area density differs from pdfLe's, except on a point or
        // spot light (pmf alone, as lightStep(x, 0)).
        if (s == 1 && !sampled.light->deltaPosition()) continue;
        source.startStream(Stream::Camera);
        source.seek(2);
        const Path x = veach::bdptStrategyPath(ws.light.data(), s, ws.camera.data(), t, sampled, source.next2D());
        Vec2 r2;
        const Color f = space.f(x, &r2);
        double p = space.lensDensity();
        for (int i = 0; i < s; ++i) p *= space.lightStep(x, i);
        for (int i = 1; i < s - 1;) {  // light-traced specular runs: light-free -> canonical
          if (!x.v[i].specular) {
            ++i;
            continue;
          }
          int r1 = i;
          while (x.v[r1 + 1].specular) ++r1;
          p *= veach::lightChainToCanonical(x, i, r1);
          a.lightChains += 1;
          a.deltaLightChains += i == 1 && veach::isDeltaPositionLight(x.v[0]);
          i = r1 + 1;
        }
        for (int i = s; i < x.k(); ++i) p *= space.eyeStep(x, i);
        const double expect = luminance(C), got = p > 0 ? luminance(f) / p : 0.0;
        const double rel = std::fabs(got - expect) / expect;
        ++a.compared;
        a.deltaLight += veach::isDeltaPositionLight(x.v[0]);
        bool specular = false;
        for (const auto& v : x.v) specular |= v.specular;
        a.withSpecular += specular;
        // Specular chains: f re-derives directions from float vertex positions, while the random walk
        // traced from offset ray origins (1e-4 scene units): Fresnel and cosines then differ by up to ~2%
        // on chains of several refractions. Elsewhere the two agree to float precision.
        const double tol = specular ? 3e-2 : 1e-3;
        if (rel < tol && std::fabs(r2.x - pr.x) < 1e-2f && std::fabs(r2.y - pr.y) < 1e-2f) ++a.agreed;
        else {
          a.worst = std::max(a.worst, rel);
          if (getenv("VEACH_DEBUG")) {
            std::printf("mismatch s=%d t=%d spec=%d ratio=%.6g f=%g p=%g raster (%g %g) vs (%g %g) flags:", s, t, int(specular), got / expect, luminance(f), p, r2.x, r2.y, pr.x, pr.y);
            for (const auto& v : x.v) std::printf(" %d%s", int(v.kind), v.specular ? "S" : "");
            std::printf("\n");
          }
        }
      }
    }
  }
  return a;
}

TEST(VeachPath, ContributionOverDensityIsBdptsUnweightedContributionDiffuse) {
  const auto scene = RenderScene::build(test::smallCornellBox(16, 16));
  const Agreement a = compareStrategies(*scene, 5, 11, 3000);
  std::printf("diffuse box: %d strategies compared, %d agree (worst rel. error of the others %.3g)\n", a.compared,
              a.agreed, a.worst);
  ASSERT_GT(a.compared, 3000);
  EXPECT_GE(a.agreed, int(0.999 * a.compared));
}

TEST(VeachPath, ContributionOverDensityIsBdptsUnweightedContributionSpecularChains) {
  const auto scene = RenderScene::build(test::cornellBoxSpecular(16, 16, /*smoothNormals=*/true));
  const Agreement a = compareStrategies(*scene, 6, 12, 4000);
  std::printf("glass + mirror box: %d strategies compared (%d with specular vertices, %d light-traced specular "
              "runs), %d agree (worst %.3g)\n", a.compared, a.withSpecular, a.lightChains, a.agreed, a.worst);
  ASSERT_GT(a.withSpecular, 300);
  ASSERT_GT(a.lightChains, 100);
  EXPECT_GE(a.agreed, int(0.995 * a.compared));
}

// Point and spot lights (path.h, delta-position lights): x_0 has density pmf, emits its intensity, is never
// reached from the eye; a specular run next to it stays light-free. Every strategy bdpt has for them (s >= 1;
// s = 0 cannot hit a point) gives C(s, t) = f / p, including light-traced caustic chains from the point.
TEST(VeachPath, ContributionOverDensityIsBdptsUnweightedContributionPointAndSpotLights) {
  const auto diffuse = RenderScene::build(test::cornellBoxPointSpot(16, 16));
  const Agreement a = compareStrategies(*diffuse, 5, 13, 3000);
  std::printf("point + spot, diffuse box: %d strategies compared (%d from a delta light), %d agree (worst %.3g)\n",
              a.compared, a.deltaLight, a.agreed, a.worst);
  ASSERT_GT(a.deltaLight, 3000);
  EXPECT_EQ(a.deltaLight, a.compared);
  EXPECT_GE(a.agreed, int(0.999 * a.compared));

  const auto specular = RenderScene::build(test::cornellBoxSpecularPointSpot(16, 16));
  const Agreement b = compareStrategies(*specular, 6, 14, 4000);
  std::printf("point + spot, glass + mirror box: %d strategies compared (%d with specular vertices, %d light-traced "
              "specular runs, %d of them next to the light), %d agree (worst %.3g)\n", b.compared, b.withSpecular,
              b.lightChains, b.deltaLightChains, b.agreed, b.worst);
  ASSERT_GT(b.withSpecular, 300);
  ASSERT_GT(b.deltaLightChains, 100);
  EXPECT_GE(b.agreed, int(0.995 * b.compared));
}

// The point light seen directly by the pinhole (L E, in the camera's view) has measure zero: f = 0, as
// bdpt has no strategy for it. (With f > 0 the bidirectional mutation proposed it and the chains piled up
// on the light's pixel: veach_chain_test's PointLight failed with z = 53.)
TEST(VeachPath, PointLightSeenDirectlyHasNoContribution) {
  const auto scene = RenderScene::build(test::cornellBoxPointSpot(16, 16));
  const PathSpace space(*scene, 5);
  Path x;
  veach::PathVertex light;
  light.kind = veach::VertexKind::Light;
  light.lightIndex = 0;
  light.light = &scene->light(0);
  ASSERT_TRUE(light.light->deltaPosition());
  light.p = Vec3(-0.3f, 0.8f, 0.0f);  // cornellBoxPointSpot's point light
  x.uLens = Vec2(0.5f, 0.5f);
  Vec3 dir;
  x.v = {light, space.cameraVertex(Vec2(8, 8), x.uLens, &dir)};
  Vec2 raster;
  EXPECT_TRUE(space.raster(x, &raster)) << "the light is in the camera's view";
  EXPECT_TRUE(space.f(x, nullptr).isBlack());
}

TEST(VeachPath, StartPathReplaysTheBootstrapValue) {
  const auto scene = RenderScene::build(test::cornellBoxSpecular(16, 16));
  IntegratorSettings integrator;
  integrator.maxDepth = 6;
  const PathSpace space(*scene, integrator.maxDepth);
  const auto bdpt = makeEvaluator(*scene, "bdpt", integrator);  // pssmlt-bdpt's target
  PathContribution pc;
  int started = 0, carrying = 0;
  for (uint64_t i = 0; i < 400; ++i) {
    IndependentSource a = IndependentSource::candidate(7, i), b = IndependentSource::candidate(7, i);
    bdpt->evaluate(a, nullptr, pc);
    const double c = targetFunction(pc);
    const std::optional<veach::StartPath> sp = veach::startPathFromSample(space, integrator, b, 0.37);
    if (c > 0) ++carrying;
    if (!sp) continue;
    ++started;
    EXPECT_EQ(sp->candidateC, c) << "candidate " << i;
    EXPECT_GT(luminance(space.f(sp->path, nullptr)), 0.0f);
  }
  EXPECT_GT(carrying, 50);
  EXPECT_GE(started, int(0.98 * carrying));
}

}  // namespace
}  // namespace mlt
