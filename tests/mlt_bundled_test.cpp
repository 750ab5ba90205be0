// The Markov chain methods agree with bdpt on the bundled scenes themselves (scenes/*.xml through the
// Mitsuba front end), at a small resolution, with their default target (luminance), twice with the
// relative one (common/mlt/importance.h; without develop.h (D8) its image mean varied 30% from run to run
// here, and the "too weak" check below failed) and twice with a tempered one (common/mlt/target.h (T1),
// c = luminance^0.6): image mean and 3x3 tile means of R independent job seeds
// (bootstrap included) against a long bdpt estimate, within kZ combined standard errors.
// With t(R - 1 = 11 dof) tails, P(|t| > 5) ~ 4e-4 per entry, ~2% over the ~60 entries here (fixed seeds).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>

#include "common/integrators/evaluators.h"
#include "common/methods/pss_method.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"
#include "tests/support/estimates.h"
#include "tests/support/mlt_stats.h"

namespace mlt {
namespace {

constexpr int kRuns = 12, kRes = 24, kTiles = 3;  // kRes divisible by kTiles: tiles of whole pixels
constexpr double kZ = 5.0;

struct Case {
  const char* scene;
  std::string method;
  double mutationsPerPixel;
  double power;  // relative image-mean error the comparison must resolve
  const char* target = kDefaultTarget;  // the chains' target (method parameter "target")
  int chains = 16;
  const char* targetPower = kDefaultTargetPower;  // method parameter "target-power"
};

// Readable test names in ctest (instead of the bytes of the struct).
void PrintTo(const Case& c, std::ostream* os) {
  *os << c.scene << " " << c.method.c_str() << " " << c.target << " power " << c.targetPower;
}

class MltBundled : public ::testing::TestWithParam<Case> {};

TEST_P(MltBundled, AgreesWithBdpt) {
  const Case c = GetParam();
  SceneDesc desc = loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + c.scene);
  desc.camera.width = desc.camera.height = kRes;
  const auto scene = RenderScene::build(desc);
  RenderSettings s;
  s.directLight = DirectLight::Chains;  // chains over every length (the automatic choice: direct_light_rule_test)
  s.method = c.method;
  s.width = s.height = kRes;
  s.integrator.maxDepth = desc.maxDepth.value_or(5);
  s.integrator.rrDepth = desc.rrDepth.value_or(5);
  s.mutationsPerPixel = c.mutationsPerPixel;
  s.bootstrapSamples = 40000;
  s.chains = c.chains;
  s.params["target"] = c.target;
  s.params["target-power"] = c.targetPower;
  const test::ImageStats mlt = test::markovChainStats(*scene, s, kRes, kRes, kRuns, kTiles);

  const auto bdpt = makeEvaluator(*scene, "bdpt", s.integrator);
  const test::ImageStats ref = test::estimateImage(*bdpt, kRes, kRes, 777, uint64_t(kRes) * kRes * 1024, kTiles, kTiles);
  int where = 0;
  const double z = test::maxZ(mlt, ref, &where);
  std::printf("%s %s: image mean %.5f +- %.5f, bdpt %.5f +- %.5f, max z %.2f\n", c.scene, c.method.c_str(),
              mlt.mean[0], mlt.stdErr[0], ref.mean[0], ref.stdErr[0], z);
  EXPECT_LT(z, kZ) << "entry " << where << " (0 = image mean) " << mlt.mean[where] << " +- " << mlt.stdErr[where]
                   << " vs bdpt " << ref.mean[where] << " +- " << ref.stdErr[where];
  EXPECT_LT(kZ * std::hypot(mlt.stdErr[0], ref.stdErr[0]), c.power * ref.mean[0]) << "test too weak";
}

INSTANTIATE_TEST_SUITE_P(Scenes, MltBundled,
                         ::testing::Values(Case{"cornell-box.xml", "pssmlt", 32, 0.08},
                                           Case{"cornell-box.xml", "pssmlt-bdpt", 16, 0.08},
                                           Case{"cornell-box.xml", "mmlt", 32, 0.08},
                                           Case{"cornell-spheres.xml", "mmlt", 32, 0.10},
                                           Case{"caustic-mirror.xml", "pssmlt", 32, 0.10},
                                           Case{"door-ajar.xml", "mmlt", 32, 0.10},
                                           Case{"cornell-box.xml", "mmlt", 32, 0.08, "relative"},
                                           Case{"door-ajar.xml", "mmlt", 32, 0.10, "relative"},
                                           Case{"cornell-box.xml", "pssmlt", 32, 0.08, kDefaultTarget, 16, "0.6"},
                                           Case{"cornell-box.xml", "mmlt", 32, 0.08, kDefaultTarget, 16, "0.6"}),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           std::string n = std::string(info.param.scene) + "_" + info.param.method.c_str();
                           n = n.substr(0, n.find('.')) + "_" + info.param.method.c_str();
                           if (std::string(info.param.target) != kDefaultTarget) n += std::string("_") + info.param.target;
                           if (std::string(info.param.targetPower) != kDefaultTargetPower)
                             n += std::string("_power") + info.param.targetPower;
                           for (char& ch : n)
                             if (ch == '-' || ch == '.') ch = '_';
                           return n;
                         });

}  // namespace
}  // namespace mlt
