// veach-mlt's job functions (common/methods/veach/veach_job.h): a chain is a pure function of (job seed,
// chain index) -- run twice, it gives the same bytes; it replays its start candidate and refuses a plan
// whose recorded c it does not reproduce; its statistics count every mutation once, per kind; the plan
// is the pssmlt-bdpt bootstrap; unsupported settings and scenes are refused with a message.
#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>

#include "common/methods/veach/veach_job.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

RenderSettings smallSettings() {
  RenderSettings s;
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
  EXPECT_FALSE(sameFilm(c0.film, c1.film));
}

TEST(VeachJob, ReplayMismatchIsRefused) {
  const auto scene = RenderScene::build(test::smallCornellBox(16, 16));
  const JobPlan plan = veach::planVeachJob(*scene, smallSettings());
  WorkUnit u = plan.units[0];
  u.startContribution *= 1.01;
  EXPECT_THROW(veach::runVeachChain(*scene, plan, u, veach::MutationSettings{}), std::runtime_error);
}

TEST(VeachJob, PlanIsThePssmltBdptBootstrap) {
  const auto scene = RenderScene::build(test::smallCornellBox(16, 16));
  RenderSettings s = smallSettings();
  const JobPlan veachPlan = veach::planVeachJob(*scene, s);
  s.method = Method::PSSMLT_BDPT;
  const JobPlan pss = planJob(*scene, s);
  EXPECT_EQ(veachPlan.norm.b, pss.norm.b);
  ASSERT_EQ(veachPlan.units.size(), pss.units.size());
  for (size_t i = 0; i < pss.units.size(); ++i) EXPECT_EQ(veachPlan.units[i].startCandidate, pss.units[i].startCandidate);
}

TEST(VeachJob, UnsupportedSettingsAndScenesAreRefused) {
  const auto box = RenderScene::build(test::smallCornellBox(16, 16));
  RenderSettings s = smallSettings();
  s.separateDirect = true;
  EXPECT_THROW(veach::planVeachJob(*box, s), std::invalid_argument);
  const auto pointLights = RenderScene::build(test::cornellBoxPointSpot(16, 16));
  EXPECT_THROW(veach::planVeachJob(*pointLights, smallSettings()), std::invalid_argument);
}

}  // namespace
}  // namespace mlt
