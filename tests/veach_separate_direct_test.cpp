// veach-mlt with the direct light rendered separately (separateDirect; common/methods/veach/veach_job.h):
// the chains cover only paths of more than kDirectMaxSegments segments (their b, bootstrap and start
// strategies leave the direct paths out exactly as pssmlt-bdpt's do), the shared pt direct pass renders
// the rest, and the image agrees with bdpt and with veach-mlt without separateDirect.
//
// Tolerance as veach_bundled_test: R job seeds per configuration (bootstrap and direct pass included), the
// standard error from their spread; max z over the image mean and 3x3 tile means below kZ (t with 11 dof:
// P(|t| > 5) ~ 4e-4 per entry); a power check that a 10% brightness error would be seen.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "common/integrators/evaluators.h"
#include "common/job/mlt_job.h"
#include "common/methods/registry.h"
#include "common/methods/veach/veach_chain.h"
#include "common/methods/veach/veach_method.h"
#include "common/methods/veach/veach_job.h"
#include "common/mlt/develop.h"
#include "common/mlt/target.h"
#include "common/render/render_scene.h"
#include "tests/support/estimates.h"
#include "tests/support/test_scenes.h"
#include "tests/support/veach_stats.h"

namespace mlt {
namespace {

constexpr int kRuns = 12, kRes = 24, kTiles = 3;
constexpr double kZ = 5.0;

const RenderScene& specularBox() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::cornellBoxSpecular(kRes, kRes));
  return *scene;
}

RenderSettings settings(bool separateDirect) {
  RenderSettings s;
  s.method = "veach-mlt";
  s.width = s.height = kRes;
  s.integrator.maxDepth = 5;
  s.mutationsPerPixel = 16;
  s.bootstrapSamples = 20000;
  s.chains = 16;
  s.directLight = separateDirect ? DirectLight::Separate : DirectLight::Chains;
  s.spp = 16;  // the direct pass
  return s;
}

std::vector<Color> render(const RenderScene& scene, const RenderSettings& s, JobPlan* planOut = nullptr) {
  const JobPlan plan = planJob(scene, s);
  PartialResult merged;
  for (const WorkUnit& u : plan.units) merged.add(runWorkUnit(scene, plan, u));
  if (planOut) *planOut = plan;
  return developImage(plan, merged);
}

// The plan is pssmlt-bdpt's with separateDirect: the same b (direct paths left out of every candidate's
// c), the same chains and start candidates, then the direct pass's bdpt batches.
// (Without the light-view pass, whose paths pssmlt-bdpt's target keeps.)
TEST(VeachSeparateDirect, PlanLeavesTheDirectPathsToTheDirectPass) {
  const RenderScene& scene = specularBox();
  RenderSettings noViews = settings(true);
  noViews.params["veach-light-view"] = "0";
  const JobPlan sd = planJob(scene, noViews);
  const JobPlan all = planJob(scene, settings(false));
  RenderSettings p = settings(true);
  p.method = "pssmlt-bdpt";
  const JobPlan pss = planJob(scene, p);
  EXPECT_EQ(sd.norm.b, pss.norm.b);
  EXPECT_LT(sd.norm.b, 0.8 * all.norm.b);  // the direct light is most of this box's brightness
  ASSERT_EQ(sd.units.size(), pss.units.size());
  int direct = 0;
  for (size_t i = 0; i < sd.units.size(); ++i) {
    EXPECT_EQ(sd.units[i].startCandidate, pss.units[i].startCandidate);
    EXPECT_EQ(sd.units[i].mutations, pss.units[i].mutations);
    direct += isDirectUnit(sd.units[i]) ? 1 : 0;
  }
  EXPECT_GT(direct, 0);
  EXPECT_EQ(sd.settings.chains + direct, int(sd.units.size()));

  // Start paths: every strategy a chain can start from is longer than the direct pass's, and the
  // candidate's c is the bootstrap target's (which leaves the direct paths out).
  const veach::PathSpace space(scene, 5, chainMinLength(sd.settings));
  const VeachMltMethod method;
  const auto target = method.makeTarget(scene, sd.settings);
  PathContribution c;
  int starts = 0;
  for (uint64_t i = 0; i < 400; ++i) {
    IndependentSource a = IndependentSource::candidate(sd.settings.seed, i), b = a;
    target->evaluate(b, -1, c);
    const auto sp = veach::startPathFromSample(space, sd.settings.integrator, a, 0.37);
    if (!sp) continue;
    ++starts;
    EXPECT_GT(sp->path.k(), kDirectMaxSegments);
    EXPECT_EQ(sp->candidateC, targetFunction(c)) << "candidate " << i;
  }
  EXPECT_GT(starts, 50);
}

TEST(VeachSeparateDirect, SameSeedSameBytes) {
  RenderSettings s = settings(true);
  s.width = s.height = 16;
  s.chains = 4;
  s.mutationsPerPixel = 8;
  s.bootstrapSamples = 4000;
  const auto scene = RenderScene::build(test::cornellBoxSpecular(16, 16));
  const std::vector<Color> a = render(*scene, s), b = render(*scene, s);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Color)), 0);
  s.seed += 1;
  const std::vector<Color> c = render(*scene, s);
  EXPECT_NE(std::memcmp(a.data(), c.data(), a.size() * sizeof(Color)), 0);
}

TEST(VeachSeparateDirect, AgreesWithBdptAndWithVeachMltWithoutIt) {
  const RenderScene& scene = specularBox();
  std::string acceptance;
  const test::ImageStats sd =
      test::veachStats(scene, settings(true), veach::MutationSettings{}, kRuns, kTiles, 2000, &acceptance);
  const test::ImageStats all = test::veachStats(scene, settings(false), veach::MutationSettings{}, kRuns, kTiles, 3000);
  IntegratorSettings is;
  is.maxDepth = 5;
  const auto bdpt = makeEvaluator(scene, "bdpt", is);
  const test::ImageStats ref = test::estimateImage(*bdpt, kRes, kRes, 777, uint64_t(kRes) * kRes * 512, kTiles, kTiles);
  int where = 0;
  const double z = test::maxZ(sd, ref, &where);
  std::printf("veach-mlt separateDirect: image mean %.5f +- %.5f, without %.5f +- %.5f, bdpt %.5f +- %.5f, max z %.2f; "
              "acceptance %s\n", sd.mean[0], sd.stdErr[0], all.mean[0], all.stdErr[0], ref.mean[0], ref.stdErr[0], z,
              acceptance.c_str());
  EXPECT_LT(z, kZ) << "entry " << where << " (0 = image mean) " << sd.mean[where] << " +- " << sd.stdErr[where]
                   << " vs bdpt " << ref.mean[where] << " +- " << ref.stdErr[where];
  const double zAll = test::maxZ(sd, all, &where);
  EXPECT_LT(zAll, kZ) << "entry " << where << " separateDirect " << sd.mean[where] << " +- " << sd.stdErr[where]
                      << " vs without " << all.mean[where] << " +- " << all.stdErr[where];
  EXPECT_LT(kZ * std::hypot(sd.stdErr[0], ref.stdErr[0]), 0.10 * ref.mean[0]) << "test too weak";
}

}  // namespace
}  // namespace mlt
