// BDPT's pieces: MIS weights of one path sum to one over the strategies that can produce it (balance and
// power heuristics, with and without specular vertices); the densities recorded by the random walks equal
// the ones recomputed from the finished path; every technique (s,t) alone, unweighted, is an unbiased
// estimator of the light carried by paths of s+t-1 segments (compared with path tracing); the MIS-weighted
// techniques of one length sum to the same value (what MMLT relies on).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "common/integrators/bdpt.h"
#include "common/integrators/path_tracer.h"
#include "common/render/render_scene.h"
#include "tests/support/estimates.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

constexpr double kZ = 5.0;

// A full path x_0 (camera) ... x_{n-1} (on an emitter) from a camera random walk, with the densities of
// every vertex as sampled from the camera side (camFwd) and from the light side (lightFwd), recomputed
// from the geometry with the Vertex density functions.
struct FullPath {
  std::vector<Vertex> x;
  std::vector<float> camFwd, lightFwd;
};

bool findPath(const RenderScene& scene, int n, uint64_t seed, bool wantSpecular, FullPath* out) {
  std::vector<Vertex> cam(n);
  for (uint64_t i = 0; i < 200000; ++i) {
    IndependentSource src(seed, i);
    Vec2 raster;
    if (generateCameraSubpath(scene, src, nullptr, n, -1, cam.data(), &raster) != n) continue;
    const Vertex& last = cam[n - 1];
    if (last.type != VertexType::Surface || !last.light || last.Le(scene, cam[n - 2]).isBlack()) continue;
    bool specular = false;
    for (int k = 1; k < n - 1; ++k) specular |= cam[k].delta;
    if (specular != wantSpecular) continue;
    FullPath& P = *out;
    P.x = cam;
    P.camFwd.assign(n, 0);
    P.lightFwd.assign(n, 0);
    for (int k = 1; k < n; ++k) P.camFwd[k] = P.x[k - 1].delta ? 0.f : P.x[k - 1].pdf(scene, k >= 2 ? &P.x[k - 2] : nullptr, P.x[k]);
    // The light side: x_{n-1} as a light origin, then emission, then BSDF sampling toward the camera.
    Vertex lightV = P.x[n - 1];
    lightV.type = VertexType::Light;
    lightV.ns = lightV.ng;
    P.lightFwd[n - 1] = lightV.pdfLightOrigin(scene, P.x[n - 2]);
    P.lightFwd[n - 2] = lightV.pdfLight(scene, P.x[n - 2]);
    for (int k = n - 3; k >= 1; --k) {
      Vertex v = P.x[k + 1];
      v.importance = true;
      P.lightFwd[k] = v.delta ? 0.f : v.pdf(scene, k + 2 == n - 1 ? &lightV : &P.x[k + 2], P.x[k]);
    }
    return true;
  }
  return false;
}

// Splits the path into the subpaths of strategy (s, t) and returns its MIS weight, or -1 when the
// strategy cannot produce the path (a connection at a delta vertex).
float weightOf(const RenderScene& scene, const FullPath& P, int s, MisHeuristic h) {
  const int n = int(P.x.size()), t = n - s;
  std::vector<Vertex> cam(std::max(t, 1)), light(std::max(s, 1));
  for (int k = 0; k < t; ++k) {
    cam[k] = P.x[k];
    cam[k].pdfFwd = P.camFwd[k];
    cam[k].pdfRev = P.lightFwd[k];
  }
  for (int j = 0; j < s; ++j) {
    const int k = n - 1 - j;
    Vertex v = P.x[k];
    v.importance = true;
    v.pdfFwd = P.lightFwd[k];
    v.pdfRev = P.camFwd[k];
    if (j == 0) {
      v.type = VertexType::Light;
      v.ns = v.ng;
    } else {
      v.wo = normalize(P.x[k + 1].p - v.p);
    }
    light[j] = v;
  }
  // Connection vertices must be able to connect.
  if (s >= 1 && t >= 2 && (!cam[t - 1].isConnectible() || (s >= 2 && !light[s - 1].isConnectible()))) return -1;
  if (t == 1 && !light[s - 1].isConnectible()) return -1;
  Vertex sampled;
  if (s == 1) sampled = light[0];
  if (t == 1) {
    sampled = P.x[0];
  }
  return misWeight(scene, light.data(), s, cam.data(), t, sampled, h);
}

void expectWeightsSumToOne(const RenderScene& scene, int n, bool specular, uint64_t seed) {
  FullPath P;
  ASSERT_TRUE(findPath(scene, n, seed, specular, &P)) << "no path of " << n << " vertices found";
  // The walk's own densities agree with the recomputed ones.
  for (int k = 1; k < n; ++k) {
    if (P.x[k - 1].delta) continue;
    EXPECT_NEAR(P.x[k].pdfFwd, P.camFwd[k], 1e-2f * P.camFwd[k] + 1e-6f) << "vertex " << k;
  }
  for (int k = 1; k <= n - 3; ++k) {
    if (P.x[k + 1].delta) continue;
    EXPECT_NEAR(P.x[k].pdfRev, P.lightFwd[k], 1e-2f * P.lightFwd[k] + 1e-6f) << "vertex " << k;
  }
  for (MisHeuristic h : {MisHeuristic::Balance, MisHeuristic::Power}) {
    double sum = 0;
    int used = 0;
    for (int s = 0; s <= n - 1; ++s) {
      if (s == 1 && n - s == 1) continue;
      const float w = weightOf(scene, P, s, h);
      if (w < 0) continue;
      EXPECT_GE(w, 0.0f);
      EXPECT_LE(w, 1.0f + 1e-5f);
      sum += w;
      ++used;
    }
    EXPECT_NEAR(sum, 1.0, 1e-4) << "n = " << n << (h == MisHeuristic::Power ? " power" : " balance") << ", "
                                << used << " strategies";
  }
}

TEST(Bdpt, MisWeightsOfOnePathSumToOne) {
  const auto diffuse = RenderScene::build(test::smallCornellBox(16, 16));
  for (int n : {3, 4, 5, 6})
    for (uint64_t seed : {1, 2, 3}) expectWeightsSumToOne(*diffuse, n, false, seed + 10 * n);
  const auto specular = RenderScene::build(test::cornellBoxSpecular(16, 16));
  for (int n : {4, 5, 6})
    for (uint64_t seed : {1, 2}) expectWeightsSumToOne(*specular, n, true, seed + 10 * n);
  // Delta lights cannot end a camera path (s = 0); their weights are covered by the agreement tests.
}

// A sphere light sampled by its cone: the strategy s = 1 has another density of the light's point than
// the strategies s >= 2 (misWeight's factor k); the weights must still sum to one.
TEST(Bdpt, MisWeightsSumToOneWithAConeSampledSphereLight) {
  const auto scene = RenderScene::build(test::cornellBoxSphereLight(16, 16));
  for (int n : {3, 4, 5})
    for (uint64_t seed : {1, 2, 3}) expectWeightsSumToOne(*scene, n, false, seed + 10 * n);
}

// ---- Each technique, unweighted, is unbiased ------------------------------------------------------
// Reference for paths of exactly k segments: pt with maxDepth k minus pt with maxDepth k-1 on the same
// primary samples (no roulette): the paths coincide up to k-1 segments, so the difference is exactly
// the light carried by k-segment paths.
test::ImageStats ptExactLength(const RenderScene& scene, int k, uint64_t seed, uint64_t n) {
  IntegratorSettings a, b;
  a.maxDepth = k;
  b.maxDepth = k - 1;
  a.rrDepth = b.rrDepth = -1;
  const PathTracer ptA(scene, a), ptB(scene, b);
  const int W = scene.camera().width(), H = scene.camera().height();
  return test::estimateImageFrom(
      [&](uint64_t i, PathContribution& c) {
        const uint64_t pix = i % uint64_t(W * H);
        const Vec2 pixel{float(pix % W), float(pix / W)};
        IndependentSource s1(seed, i), s2(seed, i);
        Vec2 r;
        const Color L = ptA.Li(s1, &pixel, &r) - ptB.Li(s2, &pixel, &r);
        c.splats.push_back(Splat{r, L, -1, -1});
      },
      W, H, n, 2, 2, -1, uint64_t(W * H));
}

test::ImageStats technique(const RenderScene& scene, int s, int t, bool weighted, uint64_t seed, uint64_t n) {
  const int W = scene.camera().width(), H = scene.camera().height();
  return test::estimateImageFrom(
      [&](uint64_t i, PathContribution& c) {
        thread_local BdptWorkspace ws;
        const uint64_t pix = i % uint64_t(W * H);
        const Vec2 pixel{float(pix % W), float(pix / W)};
        IndependentSource src(seed, i);
        const TechniqueSample ts = evaluateTechnique(scene, src, s, t, MisHeuristic::Power, ws, &pixel);
        if (!ts.C.isBlack()) c.splats.push_back(Splat{ts.pRaster, weighted ? ts.C * ts.weight : ts.C, int16_t(s), int16_t(t)});
      },
      W, H, n, 2, 2, -1, uint64_t(W * H));
}

TEST(Bdpt, EveryTechniqueAloneIsUnbiased) {
  const auto scene = RenderScene::build(test::smallCornellBox(16, 12));
  for (int k : {2, 3}) {
    const test::ImageStats ref = ptExactLength(*scene, k, 100 + k, 400000);
    std::printf("k=%d pt reference %.5f +- %.5f\n", k, ref.mean[0], ref.stdErr[0]);
    EXPECT_GT(ref.mean[0], 10 * ref.stdErr[0]);
    for (int s = 0; s <= k; ++s) {
      const int t = k + 1 - s;
      const test::ImageStats st = technique(*scene, s, t, false, 200 + 10 * k + s, s == k ? 600000 : 200000);
      const double z = test::maxZ(st, ref);
      std::printf("  (s=%d,t=%d) unweighted %.5f +- %.5f  max z %.2f\n", s, t, st.mean[0], st.stdErr[0], z);
      EXPECT_LT(z, kZ) << "technique (" << s << "," << t << ")";
    }
  }
}

TEST(Bdpt, WeightedTechniquesOfOneLengthSumToTheReference) {
  // sum over s of E[w_{s,t} C_{s,t}] = light carried by k-segment paths (MMLT's per-length integrand).
  const auto scene = RenderScene::build(test::cornellBoxSpecular(16, 12));
  const int k = 3;
  const test::ImageStats ref = ptExactLength(*scene, k, 300, 400000);
  test::ImageStats sum = ref;
  std::fill(sum.mean.begin(), sum.mean.end(), 0.0);
  std::fill(sum.stdErr.begin(), sum.stdErr.end(), 0.0);
  for (int s = 0; s <= k; ++s) {
    const test::ImageStats st = technique(*scene, s, k + 1 - s, true, 400 + s, 150000);
    for (int e = 0; e < sum.size(); ++e) {
      sum.mean[e] += st.mean[e];
      sum.stdErr[e] = std::hypot(sum.stdErr[e], st.stdErr[e]);
    }
  }
  std::printf("k=%d weighted sum %.5f +- %.5f vs pt %.5f +- %.5f\n", k, sum.mean[0], sum.stdErr[0], ref.mean[0],
              ref.stdErr[0]);
  EXPECT_LT(test::maxZ(sum, ref), kZ);
}

// evaluateLength (mmlt's b sample over every technique) is, sample by sample, the sum over s of what
// evaluateTechnique(s, k + 1 - s) gives on the same numbers, weighted: its shared subpaths' prefixes are each
// technique's subpaths. Scenes with mirror and glass (Dirac vertices inside the subpaths) and a cone-sampled
// sphere light (s = 1's density ratio); lengths 1 to 6; most samples carry light by several techniques.
TEST(Bdpt, EvaluateLengthSumsEveryTechniqueOnTheSameNumbers) {
  for (const SceneDesc& desc : {test::cornellBoxSpecular(16, 12), test::cornellBoxSphereLight(16, 12)}) {
    const auto scene = RenderScene::build(desc);
    BdptWorkspace shared, single;
    for (int k = 1; k <= 6; ++k) {
      int lit = 0, several = 0;
      for (uint64_t i = 0; i < 3000; ++i) {
        IndependentSource source(77 + uint64_t(k), i);
        const Color all = evaluateLength(*scene, source, k, MisHeuristic::Power, shared);
        Color sum;
        int techniques = 0;
        for (int s = 0; s <= k; ++s) {
          if (k == 1 && s == 1) continue;  // (1, 1) is lt's alone
          IndependentSource again(77 + uint64_t(k), i);
          const TechniqueSample ts = evaluateTechnique(*scene, again, s, k + 1 - s, MisHeuristic::Power, single);
          if (ts.weight > 0 && !ts.C.isBlack()) {
            sum += ts.C * ts.weight;
            ++techniques;
          }
        }
        const float scale = std::max({sum.r, sum.g, sum.b, 1e-30f});
        ASSERT_NEAR(all.r, sum.r, 1e-5f * scale) << "k " << k << ", sample " << i;
        ASSERT_NEAR(all.g, sum.g, 1e-5f * scale) << "k " << k << ", sample " << i;
        ASSERT_NEAR(all.b, sum.b, 1e-5f * scale) << "k " << k << ", sample " << i;
        lit += sum.isBlack() ? 0 : 1;
        several += techniques > 1 ? 1 : 0;
      }
      std::printf("k=%d: %d of 3000 samples carry light, %d by several techniques\n", k, lit, several);
      EXPECT_GT(lit, k == 1 ? 10 : 100) << "k " << k;  // k = 1: the light seen directly, small in one scene
      if (k >= 2) {
        EXPECT_GT(several, 50) << "k " << k;
      }
    }
  }
}

// The same with a cone-sampled sphere light, for k = 2 and 3 (s = 1's weight carries misWeight's k).
TEST(Bdpt, WeightedTechniquesSumToTheReferenceWithAConeSampledSphereLight) {
  const auto scene = RenderScene::build(test::cornellBoxSphereLight(16, 12));
  for (int k : {2, 3}) {
    const test::ImageStats ref = ptExactLength(*scene, k, 500 + k, 400000);
    test::ImageStats sum = ref;
    std::fill(sum.mean.begin(), sum.mean.end(), 0.0);
    std::fill(sum.stdErr.begin(), sum.stdErr.end(), 0.0);
    for (int s = 0; s <= k; ++s) {
      const test::ImageStats st = technique(*scene, s, k + 1 - s, true, 600 + 10 * k + s, 150000);
      for (int e = 0; e < sum.size(); ++e) {
        sum.mean[e] += st.mean[e];
        sum.stdErr[e] = std::hypot(sum.stdErr[e], st.stdErr[e]);
      }
    }
    std::printf("k=%d weighted sum %.5f +- %.5f vs pt %.5f +- %.5f\n", k, sum.mean[0], sum.stdErr[0], ref.mean[0],
                ref.stdErr[0]);
    EXPECT_GT(ref.mean[0], 10 * ref.stdErr[0]);
    EXPECT_LT(test::maxZ(sum, ref), kZ) << "k = " << k;
    // The cone's next-event estimate alone (s = 1, unweighted) is unbiased too.
    const test::ImageStats nee = technique(*scene, 1, k, false, 700 + k, 200000);
    EXPECT_LT(test::maxZ(nee, ref), kZ) << "s = 1 unweighted, k = " << k;
  }
}

}  // namespace
}  // namespace mlt
