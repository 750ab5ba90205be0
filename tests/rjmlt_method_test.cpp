// `--method rjmlt` through the registry and the job API (plan -> units -> merge -> develop), against bdpt:
// image mean and 3x3 tile means (luminance) of R independent job seeds (bootstrap included) compared with
// a bdpt estimate, max z = |difference| / combined standard error < kZ (as tests/mlt_render_test.cpp).
// Scenes: two lights of very different size and power (a dim panel and a small bright light in a mirror
// reflector), a thin-lens camera, and the bundled scenes at 12x12. Prints each run's acceptance per
// mutation kind and, per path length, all kinds together, next to mmlt's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "common/integrators/evaluators.h"
#include "common/methods/chain_report.h"
#include "common/methods/image_metadata.h"
#include "common/methods/registry.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"
#include "tests/support/estimates.h"
#include "tests/support/mlt_stats.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

constexpr int kRuns = 8;
constexpr double kZ = 5.0;  // t with 7 dof: P(|t| > 5) ~ 1.6e-3 per entry
constexpr int kRes = 12, kTiles = 3;

TEST(RjmltMethod, IsRegisteredWithItsKindsAndParams) {
  ASSERT_TRUE(hasMethod("rjmlt"));
  EXPECT_TRUE(isMarkovChainMethod("rjmlt"));
  EXPECT_EQ(mutationKindNames("rjmlt"), (std::vector<std::string>{"large", "small", "technique"}));
  const auto params = findMethod("rjmlt").params();  // the family's target parameters, then its own
  ASSERT_EQ(params.size(), 5u);
  EXPECT_EQ(params[0].name, "target");
  EXPECT_EQ(params[1].name, "target-floor");
  EXPECT_EQ(params[2].name, "target-power");
  EXPECT_EQ(params[3].name, "technique-step");
  EXPECT_EQ(params[4].name, "b-sample-every");  // mmlt's (mmlt_method.h, develop.h (D9))
  RenderSettings s;
  s.method = "rjmlt";
  s.largeStepProb = 0.97f;
  s.params["technique-step"] = "0.05";
  EXPECT_THROW(findMethod("rjmlt").validate(s), std::invalid_argument);
}

// A large-step probability left to the method (the default settings, the CLI without --large-step, a
// negative value on the wire) is rjmlt's 10% (the 10 / 85 / 5; measured better than 30% on the
// four bundled scenes, docs/SWEEP.md) and 30% for the other chain methods; the plan holds the value used,
// and a value that is given wins.
TEST(RjmltMethod, LargeStepDefaultIsTheMethodsAndThePlanHoldsIt) {
  const auto scene = RenderScene::build(test::smallCornellBox(8, 8));
  RenderSettings s;
  EXPECT_LT(s.largeStepProb, 0.0f);  // left to the method
  s.integrator.maxDepth = 3;
  s.mutationsPerPixel = 2;
  s.chains = 2;
  s.bootstrapSamples = 256;
  for (const auto& [method, expected] : {std::pair<std::string, float>{"rjmlt", 0.1f}, {"mmlt", 0.3f},
                                         {"pssmlt", 0.3f}, {"pssmlt-bdpt", 0.3f}}) {
    s.method = method;
    EXPECT_EQ(planJob(*scene, s).settings.largeStepProb, expected) << method;
    RenderSettings given = s;
    given.largeStepProb = 0.2f;
    EXPECT_EQ(planJob(*scene, given).settings.largeStepProb, 0.2f) << method;
  }
  // rjmlt's check of large + technique <= 1 uses the default when the large step is left to it.
  s.method = "rjmlt";
  s.params["technique-step"] = "0.85";
  EXPECT_NO_THROW(findMethod("rjmlt").validate(s));
  s.params["technique-step"] = "0.95";  // 0.1 + 0.95 > 1
  EXPECT_THROW(findMethod("rjmlt").validate(s), std::invalid_argument);
}

// Acceptance per mutation kind per path length (the issue: "per-kind acceptance statistics per path
// length"): every chain counts its kinds in its length's slot; the merged counts sum over the chains, reach
// the image metadata (techniqueSteps<k>, acceptanceTechnique<k>, ...) and read back, and the per-length
// kinds add up to the per-length and per-kind totals. No technique change at length 1 (one technique).
TEST(RjmltMethod, AcceptancePerKindPerPathLengthReachesTheMetadata) {
  const auto scene = RenderScene::build(test::smallCornellBox(8, 8));
  RenderSettings s;
  s.method = "rjmlt";
  s.integrator.maxDepth = 4;
  s.mutationsPerPixel = 64;
  s.chains = 8;
  s.bootstrapSamples = 2048;
  s.params["technique-step"] = "0.2";
  const JobPlan plan = planJob(*scene, s);
  PartialResult merged;
  std::vector<uint64_t> byLengthKind;
  for (const WorkUnit& u : plan.units) {
    const PartialResult r = runWorkUnit(*scene, plan, u);
    for (size_t i = 0; i < r.stats.proposedPerLengthKind.size(); ++i) {
      if (byLengthKind.size() <= i) byLengthKind.resize(i + 1, 0);
      byLengthKind[i] += r.stats.proposedPerLengthKind[i];
    }
    merged.add(r);
  }
  ASSERT_EQ(merged.stats.proposedPerLengthKind, byLengthKind);
  const size_t stride = ChainStats::kKindStride;
  uint64_t technique = 0;
  for (size_t k = 1; k < merged.stats.proposedPerLength.size(); ++k) {
    uint64_t sum = 0;
    for (size_t kind = 0; kind < 3; ++kind) sum += merged.stats.proposedPerLengthKind[k * stride + kind];
    EXPECT_EQ(sum, merged.stats.proposedPerLength[k]) << "length " << k;
    technique += merged.stats.proposedPerLengthKind[k * stride + 2];
  }
  EXPECT_EQ(technique, merged.stats.proposedPerKind[2]);
  const ImageMetadata m = imageMetadata(plan, merged, "test scene", "0");
  EXPECT_EQ(m.numbers.count("techniqueSteps1"), 0u);  // one technique at length 1: nothing to change
  ASSERT_TRUE(m.numbers.count("techniqueSteps3") && m.numbers.count("acceptanceTechnique3"));
  EXPECT_EQ(m.numbers.at("techniqueSteps3"), double(merged.stats.proposedPerLengthKind[3 * stride + 2]));
  EXPECT_GT(m.numbers.at("acceptanceTechnique3"), 0.5);  // the jumps keep the path: nearly always accepted
  const ChainReport back = chainReportFromMetadata(m);
  bool found = false;
  for (const ChainLengthReport& l : back.lengths)
    if (l.k == 3) {
      found = true;
      ASSERT_EQ(l.kinds.size(), 3u);
      EXPECT_EQ(l.kinds[2].first, merged.stats.proposedPerLengthKind[3 * stride + 2]);
      EXPECT_EQ(l.kinds[2].second, m.numbers.at("acceptanceTechnique3"));
    }
  EXPECT_TRUE(found);
  EXPECT_NE(formatChainSummary(back, 1, 1).find("technique "), std::string::npos) << formatChainSummary(back, 1, 1);
}

RenderSettings settings(const std::string& method, int maxDepth, double mutationsPerPixel = 48, int chains = 12) {
  RenderSettings s;
  s.method = method;
  s.integrator.maxDepth = maxDepth;
  s.mutationsPerPixel = mutationsPerPixel;
  s.bootstrapSamples = 20000;
  s.chains = chains;
  s.largeStepProb = 0.1f;  // the 10 / 85 / 5 %
  s.params.clear();
  return s;
}

void printAcceptance(const RenderScene& scene, RenderSettings s) {
  s.width = s.height = kRes;
  const JobPlan plan = planJob(scene, s);
  PartialResult merged;
  ASSERT_TRUE(runUnits(scene, plan, 0, uint32_t(plan.units.size()), merged));
  const auto kinds = mutationKindNames(s.method);
  std::printf("    %-6s", s.method.c_str());
  for (size_t k = 0; k < kinds.size() && k < merged.stats.proposedPerKind.size(); ++k)
    std::printf(" %s %.3f (%llu)", kinds[k].c_str(),
                double(merged.stats.acceptedPerKind[k]) / double(std::max<uint64_t>(1, merged.stats.proposedPerKind[k])),
                (unsigned long long)merged.stats.proposedPerKind[k]);
  std::printf(" | per length:");
  for (size_t k = 1; k < merged.stats.proposedPerLength.size(); ++k)
    if (merged.stats.proposedPerLength[k] > 0)
      std::printf(" %zu: %.3f", k,
                  double(merged.stats.acceptedPerLength[k]) / double(merged.stats.proposedPerLength[k]));
  std::printf("\n");
}

void expectAgreesWithBdpt(const std::string& name, const SceneDesc& desc, int maxDepth, double mpp = 48,
                          int chains = 12) {
  const auto scene = RenderScene::build(desc);
  const test::ImageStats rj =
      test::markovChainStats(*scene, settings("rjmlt", maxDepth, mpp, chains), kRes, kRes, kRuns, kTiles);
  IntegratorSettings is;
  is.maxDepth = maxDepth;
  const BdptEvaluator bdpt(*scene, is);
  const test::ImageStats ref = test::estimateImage(bdpt, kRes, kRes, 4242, uint64_t(kRes) * kRes * 1024, kTiles, kTiles);
  int where = 0;
  const double z = test::maxZ(rj, ref, &where);
  std::printf("[ %-16s ] rjmlt %.5f +- %.5f, bdpt %.5f +- %.5f, max z %.2f (entry %d)\n", name.c_str(), rj.mean[0],
              rj.stdErr[0], ref.mean[0], ref.stdErr[0], z, where);
  EXPECT_LT(z, kZ) << name << ": entry " << where << " rjmlt " << rj.mean[where] << " +- " << rj.stdErr[where]
                   << " vs bdpt " << ref.mean[where] << " +- " << ref.stdErr[where];
  printAcceptance(*scene, settings("rjmlt", maxDepth));
  printAcceptance(*scene, settings("mmlt", maxDepth));
}

TEST(RjmltMethod, TwoLightsOfVeryDifferentSizeAndPowerAgreesWithBdpt) {
  expectAgreesWithBdpt("two-lights", test::twoLightsReflector(kRes, kRes), 5);
}

TEST(RjmltMethod, ThinLensAgreesWithBdpt) {
  SceneDesc d = test::smallCornellBox(kRes, kRes);
  d.camera.type = CameraDesc::Type::ThinLens;
  d.camera.apertureRadius = 0.3f;
  d.camera.focusDistance = 3.0f;
  expectAgreesWithBdpt("thin-lens", d, 5);
}

class RjmltMethodBundled : public ::testing::TestWithParam<const char*> {};

TEST_P(RjmltMethodBundled, AgreesWithBdpt) {
  const std::string file = std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + GetParam() + ".xml";
  SceneDesc desc = loadMitsubaScene(file, {{"res", std::to_string(kRes)}});
  desc.camera.width = desc.camera.height = kRes;
  // door-ajar and glossy-plates: rjmlt's small steps keep the technique and their large steps are almost
  // never accepted (0.7% / 1.4%), so its chains cover the image more slowly than mmlt's; at mmlt's
  // 48 mutations per pixel x 12 chains two tiles were off by 8 standard errors (of the spread over runs,
  // which misses a region all runs under-visit). Longer runs converge (see docs/RJMLT.md).
  const bool slow = std::string(GetParam()) == "door-ajar" || std::string(GetParam()) == "glossy-plates";
  expectAgreesWithBdpt(GetParam(), desc, 4, slow ? 256 : 48, slow ? 32 : 12);
}

INSTANTIATE_TEST_SUITE_P(Bundled, RjmltMethodBundled,
                         ::testing::Values("cornell-box", "cornell-spheres", "door-ajar", "glossy-plates",
                                           "caustic-mirror", "furnace-sphere"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string n = info.param;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

}  // namespace
}  // namespace mlt
