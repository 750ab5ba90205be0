// The direct-light rule (common/job/direct_light_rule.h): its pilot is a pure function of its inputs, its
// share is the image's (bdpt rendered at max depth 2 against the full depth), and it tells a smooth
// direct light from a spiky or absent one on the bundled scenes it was read from; a job left to the plan
// (DirectLight::Auto) is the job with the pilot's choice given explicitly, bit for bit.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/integrators/evaluators.h"
#include "common/job/direct_light_rule.h"
#include "common/job/mlt_job.h"
#include "common/methods/chain_report.h"
#include "common/methods/pss_method.h"
#include "common/methods/registry.h"
#include "common/render/render_scene.h"
#include "common/scene/scene_loader.h"
#include "tests/support/estimates.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

RenderSettings pilotSettings(int width, int height, int maxDepth, uint64_t seed) {
  RenderSettings s;
  s.method = "mmlt";
  s.width = width;
  s.height = height;
  s.integrator.maxDepth = maxDepth;
  s.seed = seed;
  return s;
}

// A bundled scene on a res x res film, and a pilot's settings for it at the scene's own max depth.
struct BundledPilot {
  std::unique_ptr<RenderScene> scene;
  RenderSettings settings;
};
BundledPilot bundledPilot(const std::string& file, int res, uint64_t seed) {
  SceneDesc desc = loadScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + file);
  desc.camera.width = desc.camera.height = res;
  return {RenderScene::build(desc), pilotSettings(res, res, desc.maxDepth.value_or(5), seed)};
}

TEST(DirectLightRule, PilotIsAPureFunctionOfItsInputs) {
  const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(48, 32));
  const RenderSettings s = pilotSettings(48, 32, 5, 7);
  DirectLightPilot one, two;
  tbb::task_arena(1).execute([&] { one = directLightPilot(*scene, s); });
  tbb::task_arena(2).execute([&] { two = directLightPilot(*scene, s); });
  EXPECT_EQ(std::memcmp(&one.share, &two.share, sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(&one.cv, &two.cv, sizeof(double)), 0);
  EXPECT_EQ(one.separate, two.separate);
  EXPECT_EQ(one.samples, kPilotShareSamples + kPilotCvSamples);
  RenderSettings other = s;
  other.seed = 8;
  EXPECT_NE(directLightPilot(*scene, other).cv, one.cv);  // its own numbers, from the job's seed
}

// The pilot draws only what can change its choice: caustic-mirror (every light behind a mirror, no direct
// light) stops after the share's first samples; door-ajar (light through a gap, ~15% direct) draws the
// share's samples but not the CV's; a pilot that only sizes a pass draws every share sample and no CV; the
// share is the same number whichever use drew it.
TEST(DirectLightRule, DrawsOnlyWhatCanChangeTheChoice) {
  const auto [caustic, cs] = bundledPilot("caustic-mirror.xml", 128, 1);
  const DirectLightPilot dark = directLightPilot(*caustic, cs);
  EXPECT_LT(dark.share, kPilotShareStop);
  EXPECT_EQ(dark.cv, -1.0);
  EXPECT_EQ(dark.samples, kPilotShareFirst);
  EXPECT_TRUE(dark.decided);
  EXPECT_FALSE(dark.separate);

  const auto [door, ds] = bundledPilot("door-ajar.xml", 128, 1);
  const DirectLightPilot gap = directLightPilot(*door, ds);
  EXPECT_GE(gap.share, kPilotShareStop);
  EXPECT_LT(gap.share, kDirectMinShare);
  EXPECT_EQ(gap.cv, -1.0);
  EXPECT_EQ(gap.samples, kPilotShareSamples);
  EXPECT_FALSE(gap.separate);
  const DirectLightPilot gapSize = directLightPilot(*door, ds, PilotUse::SizePass);
  EXPECT_EQ(std::memcmp(&gap.share, &gapSize.share, sizeof(double)), 0);

  const std::unique_ptr<RenderScene> box = RenderScene::build(test::smallCornellBox(48, 32));
  const RenderSettings s = pilotSettings(48, 32, 5, 7);
  const DirectLightPilot decide = directLightPilot(*box, s);
  const DirectLightPilot size = directLightPilot(*box, s, PilotUse::SizePass);
  EXPECT_GE(decide.share, kDirectMinShare);  // a box lit from above: the CV decides
  EXPECT_GE(decide.cv, 0.0);
  EXPECT_EQ(decide.samples, kPilotShareSamples + kPilotCvSamples);
  EXPECT_EQ(std::memcmp(&decide.share, &size.share, sizeof(double)), 0);
  EXPECT_EQ(size.cv, -1.0);
  EXPECT_EQ(size.samples, kPilotShareSamples);
  EXPECT_FALSE(size.decided);
  // A pilot that sizes a pass draws every share sample even where the first ones put the share near 0.
  EXPECT_EQ(directLightPilot(*caustic, cs, PilotUse::SizePass).samples, kPilotShareSamples);
}

// A second bootstrap of the same job (a time budget's, after its probe) takes the first one's pilot only
// if it was run for the same use: a pilot that chose and stopped early (caustic-mirror) has too few of the
// share's samples to size a pass, so a bootstrap that must size one runs its own.
TEST(DirectLightRule, AnEarlierPilotIsTakenOnlyForTheSameUse) {
  auto [scene, s] = bundledPilot("caustic-mirror.xml", 64, 3);
  s.mutationsPerPixel = 4;
  const ChainJobSpec& mmlt = *findChainJobSpec("mmlt");
  const MarkovChainBootstrap first = bootstrapMarkovChainJob(mmlt, *scene, s);  // DirectLight::Auto
  ASSERT_TRUE(first.pilot);
  EXPECT_EQ(first.pilot->samples, kPilotShareFirst);
  const MarkovChainBootstrap again = bootstrapMarkovChainJob(mmlt, *scene, s, &first);
  ASSERT_TRUE(again.pilot);
  EXPECT_EQ(again.pilot->seconds, 0.0);  // taken, not run again
  EXPECT_EQ(again.pilot->samples, kPilotShareFirst);
  RenderSettings sized = s;
  sized.directLight = DirectLight::Separate;
  sized.spp = 0;
  const MarkovChainBootstrap pass = bootstrapMarkovChainJob(mmlt, *scene, sized, &first);
  ASSERT_TRUE(pass.pilot);
  EXPECT_EQ(pass.pilot->samples, kPilotShareSamples);  // its own
  EXPECT_FALSE(pass.pilot->decided);
}

// The share the pilot measures is the direct light's share of the image: bdpt limited to two segments
// against bdpt at the full depth (64 spp on a 32x32 film: their ratio's noise is far below the pilot's),
// within 4 standard errors of the mean of 8 pilots (their spread measured, not assumed).
TEST(DirectLightRule, ShareIsTheDirectLightsShareOfTheImage) {
  constexpr int kRes = 32, kDepth = 5;
  const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(kRes, kRes));
  auto imageMean = [&](int maxDepth) {
    IntegratorSettings integrator;
    integrator.maxDepth = maxDepth;
    const std::unique_ptr<PathEvaluator> bdpt = makeEvaluator(*scene, "bdpt", integrator);
    return test::estimateImage(*bdpt, kRes, kRes, 11, 64 * kRes * kRes, 1, 1).mean[0];
  };
  const double expected = imageMean(kDirectMaxSegments) / imageMean(kDepth);
  std::vector<double> shares;
  for (uint64_t seed = 1; seed <= 8; ++seed) shares.push_back(directLightPilot(*scene, pilotSettings(kRes, kRes, kDepth, seed)).share);
  double mean = 0, var = 0;
  for (double v : shares) mean += v / double(shares.size());
  for (double v : shares) var += (v - mean) * (v - mean) / double(shares.size() - 1);
  const double se = std::sqrt(var / double(shares.size()));
  std::printf("share: pilots %.4f +- %.4f, bdpt images %.4f\n", mean, se, expected);
  EXPECT_GT(expected, 0.3);  // a box lit from above: mostly direct light
  EXPECT_LT(expected, 0.95);
  EXPECT_LT(std::abs(mean - expected), 4 * se + 0.002) << "pilot share " << mean << " +- " << se << ", images " << expected;
}

// The bundled scenes the thresholds were read from, at 256x256 and their own max depth: a smooth direct
// light takes the pass (the Cornell box, textured-serialized), a spiky one (glossy-plates: small lights in
// glossy reflections) or none at all (caustic-mirror: every light behind a mirror) does not.
TEST(DirectLightRule, SmoothDirectLightTakesThePassSpikyOrAbsentDoesNot) {
  struct Case {
    std::string file;
    bool separate;
  };
  for (const Case& c : std::vector<Case>{{"cornell-box.xml", true},
                                         {"textured-serialized.xml", true},
                                         {"glossy-plates.xml", false},
                                         {"caustic-mirror.xml", false}}) {
    auto [scene, s] = bundledPilot(c.file, 256, 1);
    for (const uint64_t seed : {uint64_t(1), uint64_t(2)}) {
      s.seed = seed;
      const DirectLightPilot p = directLightPilot(*scene, s);
      std::printf("%s seed %d: share %.3f, CV %.2f, %.3f s\n", c.file.c_str(), int(seed), p.share, p.cv, p.seconds);
      EXPECT_EQ(p.separate, c.separate) << c.file << " seed " << seed << ": share " << p.share << ", CV " << p.cv;
      EXPECT_EQ(p.separate, p.share >= kDirectMinShare && p.cv <= kDirectMaxCv);
      EXPECT_GE(p.share, 0.0);
      EXPECT_LE(p.share, 1.0);
    }
  }
}

// Auto is resolved by the plan into the pilot's choice, which the plan holds (with the pass sized by the
// plan, directSppFor, whatever spp the settings carried) along with the pilot's numbers; the image is the
// one the explicit choice gives, bit for bit. A method that cannot render the direct light apart (pssmlt)
// resolves it to Chains without a pilot.
TEST(DirectLightRule, AutoIsThePlansExplicitChoice) {
  const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(24, 16));
  for (const std::string method : {"mmlt", "pssmlt-bdpt", "pssmlt"}) {
    RenderSettings s;
    s.method = method;
    s.seed = 5;
    s.integrator.maxDepth = 4;
    s.mutationsPerPixel = 12;
    s.bootstrapSamples = 4000;
    s.spp = 16;  // ignored by an automatic pass
    const JobPlan automatic = planJob(*scene, s);
    ASSERT_NE(automatic.settings.directLight, DirectLight::Auto) << method;
    const bool apart = findChainJobSpec(method)->allowsSeparateDirect();
    EXPECT_EQ(automatic.settings.directLight, apart ? DirectLight::Separate : DirectLight::Chains) << method;
    EXPECT_EQ(automatic.norm.directShare >= 0, apart) << method;
    if (apart) {
      DirectLightPilot pilot;
      pilot.share = automatic.norm.directShare;
      EXPECT_EQ(automatic.settings.spp,
                directSppFor(directSppPerMutation(*findChainJobSpec(method), automatic.settings, &pilot), s.mutationsPerPixel));
    }

    RenderSettings explicitChoice = s;
    explicitChoice.directLight = automatic.settings.directLight;
    if (separatesDirect(explicitChoice)) explicitChoice.spp = 0;
    const JobPlan given = planJob(*scene, explicitChoice);
    EXPECT_LT(given.norm.directShare, 0);  // no pilot ran
    auto render = [&](const JobPlan& plan) {
      PartialResult merged;
      for (const WorkUnit& u : plan.units) merged.add(runWorkUnit(*scene, plan, u));
      return developImage(plan, merged);
    };
    const std::vector<Color> a = render(automatic), b = render(given);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Color)), 0) << method;

    PartialResult merged;
    for (const WorkUnit& u : automatic.units) merged.add(runWorkUnit(*scene, automatic, u));
    ImageMetadata m;
    addChainMetadata(makeChainReport(automatic, merged), m);
    EXPECT_EQ(m.numbers.count("directLightShare"), apart ? 1u : 0u) << method;
    EXPECT_EQ(m.numbers.at("separateDirect"), apart ? 1.0 : 0.0) << method;
  }
}

// Where a light is small on the film and the pilot keeps the direct light in the chains, mmlt, rjmlt and
// pssmlt-bdpt render the lights seen directly by a pass of their own (DirectLight::Emission, mlt_job.h):
// glossy-plates' spheres (three of four small at 64x64). The plan has no chains of length 1 (mmlt, rjmlt),
// a pass of mutationCost x kEmissionSppPerMutation samples per mutation per pixel, and the explicit choice
// renders the same bits; the image's metadata names the choice. pssmlt, whose splats carry no path length,
// keeps the chains and is refused the choice when it is asked for, and so is veach-mlt (veach_job_test).
TEST(DirectLightRule, SmallLightsSeenDirectlyTakeAPassOfTheirOwn) {
  const BundledPilot plates = bundledPilot("glossy-plates.xml", 64, 5);
  for (const std::string method : {"mmlt", "rjmlt", "pssmlt-bdpt"}) {
    const ChainJobSpec& spec = *findChainJobSpec(method);
    RenderSettings s = plates.settings;
    s.method = method;
    s.mutationsPerPixel = 12;
    s.bootstrapSamples = 4000;
    const JobPlan automatic = planJob(*plates.scene, s);
    ASSERT_EQ(automatic.settings.directLight, DirectLight::Emission) << method;
    EXPECT_GE(automatic.norm.directShare, 0) << method << ": the pilot decided";
    EXPECT_EQ(automatic.settings.spp, directSppFor(spec.mutationCost() * kEmissionSppPerMutation, s.mutationsPerPixel))
        << method;
    if (spec.chainsPerLength()) {
      EXPECT_EQ(chainMinLength(automatic.settings), 2) << method;
      ASSERT_GT(automatic.norm.mutationsPerLength.size(), 2u) << method;
      EXPECT_EQ(automatic.norm.mutationsPerLength[1], 0u) << method << ": no chain of length 1";
    }
    size_t direct = 0;
    for (const WorkUnit& u : automatic.units) direct += isDirectUnit(u) ? 1 : 0;
    EXPECT_GT(direct, 0u) << method;

    RenderSettings explicitChoice = s;
    explicitChoice.directLight = DirectLight::Emission;
    explicitChoice.spp = 0;
    const JobPlan given = planJob(*plates.scene, explicitChoice);
    EXPECT_LT(given.norm.directShare, 0) << method << ": no pilot ran";
    auto merge = [&](const JobPlan& plan) {
      PartialResult merged;
      for (const WorkUnit& u : plan.units) merged.add(runWorkUnit(*plates.scene, plan, u));
      return merged;
    };
    const PartialResult ma = merge(automatic), mb = merge(given);
    const std::vector<Color> a = developImage(automatic, ma), b = developImage(given, mb);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Color)), 0) << method;
    ImageMetadata m;
    addChainMetadata(makeChainReport(automatic, ma), m);
    EXPECT_EQ(m.strings.at("directLight"), "emission") << method;
    EXPECT_EQ(m.numbers.at("separateDirect"), 0.0) << method << ": what files before directLight said";
    EXPECT_EQ(m.numbers.at("directSpp"), double(automatic.settings.spp)) << method;
    EXPECT_EQ(chainReportFromMetadata(m).settings.directLight, DirectLight::Emission) << method;
  }
  RenderSettings one = plates.settings;
  one.method = "pssmlt";
  one.mutationsPerPixel = 4;
  one.bootstrapSamples = 4000;
  EXPECT_EQ(planJob(*plates.scene, one).settings.directLight, DirectLight::Chains);
  one.directLight = DirectLight::Emission;
  one.spp = 0;
  try {
    planJob(*plates.scene, one);
    ADD_FAILURE() << "pssmlt took a pass of the lights seen directly";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cannot take direct light emission"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mlt
