// pt, lt and bdpt agree on the bundled scenes themselves (scenes/*.xml and *.pbrt, through loadScene),
// not only on the code-built test scenes: image mean and 3x3 tile means within kZ standard errors
// (measured from independent batches; tests/support/estimates.h), at a small resolution.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>

#include "common/integrators/evaluators.h"
#include "common/render/render_scene.h"
#include "common/scene/scene_loader.h"
#include "tests/support/estimates.h"

namespace mlt {
namespace {

using test::ImageStats;

// 5 sigma over ~10 entries x ~8 comparisons: a false alarm is ~1e-4 per run (and the seeds are fixed).
constexpr double kZ = 5.0;
constexpr int kRes = 24;

std::unique_ptr<RenderScene> loadBundled(const std::string& name, IntegratorSettings* is) {
  SceneDesc desc = loadScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + name);
  desc.camera.width = desc.camera.height = kRes;  // every bundled scene is square
  is->maxDepth = desc.maxDepth.value_or(5);
  is->rrDepth = desc.rrDepth.value_or(5);
  return RenderScene::build(desc);
}

ImageStats estimate(const RenderScene& scene, std::string m, const IntegratorSettings& is, uint64_t seed, uint64_t n) {
  const auto ev = makeEvaluator(scene, m, is);
  return test::estimateImage(*ev, kRes, kRes, seed, n, 3, 3);
}

void expectAgree(const ImageStats& a, const ImageStats& b, const std::string& what, double power) {
  int where = -1;
  const double z = test::maxZ(a, b, &where);
  std::printf("%-34s image mean %.5f +- %.5f vs %.5f +- %.5f, max z %.2f\n", what.c_str(), a.mean[0], a.stdErr[0],
              b.mean[0], b.stdErr[0], z);
  EXPECT_LT(z, kZ) << what << ": entry " << where << " (0 = image mean, else tile) " << a.mean[where] << " +- "
                   << a.stdErr[where] << " vs " << b.mean[where] << " +- " << b.stdErr[where];
  // Power: the comparison resolves an error of `power` (relative) in the image mean, or it could not fail.
  EXPECT_LT(kZ * std::hypot(a.stdErr[0], b.stdErr[0]), power * b.mean[0]) << what;
}

struct Case {
  const char* scene;
  bool lt;            // light tracing sees the scene (no specular surface directly in view)
  uint64_t nPt, nLt, nBdpt;
  double power = 0.10;  // relative image-mean error the comparison must resolve
};

// Readable test names in ctest (instead of the bytes of the struct).
void PrintTo(const Case& c, std::ostream* os) { *os << c.scene; }

class BundledScenes : public ::testing::TestWithParam<Case> {};

TEST_P(BundledScenes, PtLtAndBdptAgree) {
  const Case c = GetParam();
  IntegratorSettings is;
  const auto scene = loadBundled(c.scene, &is);
  const ImageStats bd = estimate(*scene, "bdpt", is, 101, c.nBdpt);
  const ImageStats pt = estimate(*scene, "pt", is, 102, c.nPt);
  expectAgree(pt, bd, std::string(c.scene) + ": pt vs bdpt", c.power);
  if (c.lt) {
    const ImageStats lt = estimate(*scene, "lt", is, 103, c.nLt);
    expectAgree(lt, bd, std::string(c.scene) + ": lt vs bdpt", c.power);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, BundledScenes,
                         ::testing::Values(Case{"cornell-box.xml", true, 400000, 400000, 150000},
                                           Case{"cornell-spheres.xml", false, 400000, 0, 150000},
                                           Case{"door-ajar.xml", true, 600000, 600000, 200000},
                                           // Tiny lights of radiance 1/r^2 seen directly: heavy-tailed
                                           // pixel values, so more samples and a 15% resolution.
                                           Case{"glossy-plates.xml", false, 6400000, 0, 2400000, 0.15},
                                           Case{"caustic-mirror.xml", false, 600000, 0, 200000},
                                           // Serialized meshes, a bitmap floor, textured specular
                                           // reflectance and roughness, a textured area light.
                                           Case{"textured-serialized.xml", true, 400000, 400000, 150000},
                                           // The pbrt-v3 scene (glass sphere in view: no lt).
                                           Case{"checker-spheres.pbrt", false, 400000, 0, 150000}),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           std::string n = info.param.scene;
                           n = n.substr(0, n.find('.'));
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

}  // namespace
}  // namespace mlt
