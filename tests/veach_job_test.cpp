// veach-mlt's job functions (common/methods/veach/veach_job.h): a chain is a pure function of (job seed,
// chain index) -- run twice, it gives the same bytes; it replays its start candidate and refuses a plan
// whose recorded c it does not reproduce; its statistics count every mutation once, per kind; the plan
// is the pssmlt-bdpt bootstrap; unsupported settings and scenes are refused with a message.
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/job/mlt_job.h"
#include "common/methods/image_metadata.h"
#include "common/methods/pss_method.h"
#include "common/methods/registry.h"
#include "common/methods/veach/veach_chain.h"
#include "common/methods/veach/veach_job.h"
#include "common/mlt/develop.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

RenderSettings smallSettings() {
  RenderSettings s;
  s.directLight = DirectLight::Chains;  // chains over every length (the automatic choice: direct_light_rule_test)
  s.seed = 21;
  s.width = s.height = 16;
  s.integrator.maxDepth = 5;
  s.mutationsPerPixel = 8;
  s.chains = 4;
  return s;
}

bool sameFilm(Film& a, Film& b) {
  for (size_t layer = 0; layer < std::max(a.splatLayerCount(), b.splatLayerCount()); ++layer) {
    if (a.hasSplatLayer(layer) != b.hasSplatLayer(layer)) return false;
    if (!a.hasSplatLayer(layer)) continue;
    const auto& x = a.splatLayer(layer);
    const auto& y = b.splatLayer(layer);
    if (x.size() != y.size() || std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) != 0) return false;
  }
  return true;
}

TEST(VeachJob, ChainsArePureFunctionsOfSeedAndIndex) {
  const auto scene = RenderScene::build(test::cornellBoxSpecular(16, 16));
  const JobPlan plan = veach::planVeachJob(*scene, smallSettings());
  ASSERT_EQ(plan.units.size(), 4u);
  const veach::MutationSettings mut;
  for (const WorkUnit& u : plan.units) {
    PartialResult a = veach::runVeachChain(*scene, plan, u, mut);
    PartialResult b = veach::runVeachChain(*scene, plan, u, mut);
    a.foldSplats();
    b.foldSplats();
    EXPECT_TRUE(sameFilm(a.film, b.film)) << "chain " << u.index;
    EXPECT_EQ(a.stats.acceptedPerKind, b.stats.acceptedPerKind);
    // Every mutation counted once, per kind and in the path-length slot develop reads.
    uint64_t sum = 0;
    for (uint64_t p : a.stats.proposedPerKind) sum += p;
    EXPECT_EQ(sum, u.mutations);
    ASSERT_EQ(a.stats.proposedPerLength.size(), 1u);
    EXPECT_EQ(a.stats.proposedPerLength[0], u.mutations);
    EXPECT_EQ(a.samples, u.mutations);
  }
  // Different chains differ.
  PartialResult c0 = veach::runVeachChain(*scene, plan, plan.units[0], mut);
  PartialResult c1 = veach::runVeachChain(*scene, plan, plan.units[1], mut);
  c0.foldSplats();
  c1.foldSplats();
  EXPECT_FALSE(sameFilm(c0.film, c1.film));
}

TEST(VeachJob, ReplayMismatchIsRefused) {
  const auto scene = RenderScene::build(test::smallCornellBox(16, 16));
  const JobPlan plan = veach::planVeachJob(*scene, smallSettings());
  WorkUnit u = plan.units[0];
  u.startContribution *= 1.01;
  EXPECT_THROW(veach::runVeachChain(*scene, plan, u, veach::MutationSettings{}), std::runtime_error);
}

// A start candidate that rebuilds to no path with f > 0 (door-ajar at 256x256 had one chain in ~10^3 like
// this, and the job failed) starts its chain from a path resampled from fresh candidates: the chain runs
// all its mutations, deterministically, with a finite film.
TEST(VeachJob, StartCandidateWithoutPathFallsBackToResampledStart) {
  const auto scene = RenderScene::build(test::smallCornellBox(16, 16));
  const RenderSettings settings = smallSettings();
  const JobPlan plan = veach::planVeachJob(*scene, settings);
  const veach::PathSpace space(*scene, settings.integrator.maxDepth);
  // A candidate whose bdpt sample contributes nothing (c = 0): no strategy to start from.
  uint64_t dead = 0;
  for (;; ++dead) {
    ASSERT_LT(dead, 100000u) << "no candidate with c = 0 found";
    IndependentSource source = IndependentSource::candidate(settings.seed, dead);
    if (!veach::startPathFromSample(space, settings.integrator, source, 0.5)) break;
  }
  WorkUnit u = plan.units[0];
  u.startCandidate = dead;
  u.startContribution = 0;
  PartialResult a = veach::runVeachChain(*scene, plan, u, veach::MutationSettings{});
  PartialResult b = veach::runVeachChain(*scene, plan, u, veach::MutationSettings{});
  a.foldSplats();
  b.foldSplats();
  EXPECT_EQ(a.samples, u.mutations);
  PartialResult a2 = a;
  EXPECT_TRUE(sameFilm(a2.film, b.film));
  double sum = 0;
  for (const auto& px : a.film.splatLayer(chainLayer(0))) {
    ASSERT_TRUE(std::isfinite(px.r) && std::isfinite(px.g) && std::isfinite(px.b));
    sum += px.r + px.g + px.b;
  }
  EXPECT_GT(sum, 0);
}

// (Without the light-view pass: with it, b leaves out the light seen directly, which pssmlt-bdpt keeps.)
TEST(VeachJob, PlanIsThePssmltBdptBootstrap) {
  const auto scene = RenderScene::build(test::smallCornellBox(16, 16));
  RenderSettings s = smallSettings();
  EXPECT_LT(veach::planVeachJob(*scene, s).norm.b, 0.8 * [&] {
    RenderSettings p = s;
    p.method = "pssmlt-bdpt";
    return planJob(*scene, p).norm.b;
  }());
  s.params["veach-light-view"] = "0";
  const JobPlan veachPlan = veach::planVeachJob(*scene, s);
  s.params.clear();
  s.method = "pssmlt-bdpt";
  const JobPlan pss = planJob(*scene, s);
  EXPECT_EQ(veachPlan.norm.b, pss.norm.b);
  ASSERT_EQ(veachPlan.units.size(), pss.units.size());
  for (size_t i = 0; i < pss.units.size(); ++i) EXPECT_EQ(veachPlan.units[i].startCandidate, pss.units[i].startCandidate);
}

// Through the registry and the job API, as the CLI and the farm run it: the image is the job functions'
// image, and the metadata carries the acceptance of each of the five mutations.
TEST(VeachJob, RegisteredAsVeachMlt) {
  ASSERT_TRUE(hasMethod("veach-mlt"));
  EXPECT_EQ(findMethod("veach-mlt").mutationKinds(), veach::mutationKindNames());
  EXPECT_TRUE(isMarkovChainMethod("veach-mlt"));
  const auto scene = RenderScene::build(test::cornellBoxSpecular(16, 16));
  RenderSettings s = smallSettings();
  s.method = "veach-mlt";
  const JobPlan plan = planJob(*scene, s);
  PartialResult merged, direct;
  for (const WorkUnit& u : plan.units) {
    merged.add(runWorkUnit(*scene, plan, u));
    direct.add(veach::runVeachChain(*scene, plan, u, veach::MutationSettings{}));
  }
  const std::vector<Color> a = developImage(plan, merged), b = veach::developVeachImage(plan, direct, veach::MutationSettings{});
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Color)), 0);
  const ImageMetadata m = imageMetadata(plan, merged, "test scene", "0");
  for (const std::string& kind : veach::mutationKindNames()) {
    std::string key = "acceptance" + kind;
    key[10] = char(std::toupper(key[10]));
    EXPECT_TRUE(m.numbers.count(key)) << key;
  }
  EXPECT_GT(m.numbers.at("acceptanceBidir"), 0.1);
  // A parameter of the method changes the chains: only the bidirectional mutation.
  s.params["veach-lens"] = "0";
  s.params["veach-caustic"] = "0";
  s.params["veach-multichain"] = "0";
  s.params["veach-lens-subpath"] = "0";
  const JobPlan onlyBidir = planJob(*scene, s);
  const PartialResult r = runWorkUnit(*scene, onlyBidir, onlyBidir.units[0]);
  EXPECT_EQ(r.stats.proposedPerKind[veach::kBidir], onlyBidir.units[0].mutations);
  s.params["veach-bidir"] = "0";
  EXPECT_THROW(planJob(*scene, s), std::invalid_argument);  // not ergodic
}

// b is refined as the chains run: each chain evaluates veachBSamples(mutations) independent bootstrap
// candidates (a stream of its own) into largeStepSums, which develop combines with the bootstrap's b; their
// mean agrees with the bootstrap's within the errors, and b's standard error falls as the job grows.
TEST(VeachJob, ChainsRefineBWithIndependentCandidates) {
  const auto scene = RenderScene::build(test::smallCornellBox(16, 16));
  RenderSettings s = smallSettings();
  s.method = "veach-mlt";
  double lastStdErr = 0;
  for (double mpp : {16.0, 1024.0}) {
    s.mutationsPerPixel = mpp;
    const JobPlan plan = planJob(*scene, s);
    PartialResult merged;
    for (const WorkUnit& u : plan.units) {
      const PartialResult r = runWorkUnit(*scene, plan, u);
      ASSERT_EQ(r.stats.largeStepSums.size(), 1u);
      EXPECT_EQ(r.stats.largeStepSums[0].n, veach::veachBSamples(u.mutations)) << "chain " << u.index;
      merged.add(r);
    }
    const TargetSums& large = merged.stats.largeStepSums[0];
    const double bL = large.sum / double(large.n);
    const double seL = std::sqrt(plan.norm.bootstrapB[0].sampleVar / double(large.n));
    EXPECT_NEAR(bL, plan.norm.b, 4 * std::hypot(seL, plan.norm.bStdErr)) << mpp;
    const RefinedB b = refinedB(plan.norm, merged.stats);
    EXPECT_EQ(b.total.samples, plan.norm.bootstrapSamples + large.n);
    if (lastStdErr > 0) {  // 64x the job, the same bootstrap: tighter than before and than the bootstrap alone
      EXPECT_LT(b.total.stdErr, lastStdErr);
      EXPECT_LT(b.total.stdErr, plan.norm.bStdErr);
    }
    lastStdErr = b.total.stdErr;
  }
}

TEST(VeachJob, UnsupportedSettingsAndScenesAreRefused) {
  const auto box = RenderScene::build(test::smallCornellBox(16, 16));
  RenderSettings s = smallSettings();
  s.directLight = DirectLight::Separate;
  s.spp = -1;  // not a size (0 is: the plan sizes the direct pass, directSppFor)
  EXPECT_THROW(veach::planVeachJob(*box, s), std::invalid_argument);
  s.spp = 0;
  const DirectLightPilot pilot = directLightPilot(*box, s);  // the pass is sized by its share
  EXPECT_EQ(veach::planVeachJob(*box, s).settings.spp,
            directSppFor(directSppPerMutation(*findChainJobSpec("veach-mlt"), s, &pilot), s.mutationsPerPixel));
  s.directLight = DirectLight::Emission;  // its light-view pass renders the lights seen directly
  EXPECT_THROW(veach::planVeachJob(*box, s), std::invalid_argument);
  s.directLight = DirectLight::Separate;
  // Point and spot lights are supported (path.h); directional and environment lights are refused, the
  // message naming the light and its type.
  const auto pointLights = RenderScene::build(test::cornellBoxPointSpot(16, 16));
  EXPECT_NO_THROW(veach::planVeachJob(*pointLights, smallSettings()));
  for (const auto& [type, name] : {std::pair{LightDesc::Type::Directional, "directional"},
                                   std::pair{LightDesc::Type::Constant, "environment"}}) {
    SceneDesc d = test::cornellBoxPointSpot(16, 16);
    LightDesc l;
    l.type = type;
    l.direction = Vec3(0, -1, 0);
    d.lights.push_back(l);
    const auto scene = RenderScene::build(d);
    try {
      veach::planVeachJob(*scene, smallSettings());
      ADD_FAILURE() << name << " light accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("light 2"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace mlt
