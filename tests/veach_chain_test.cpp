// veach-mlt chains converge to the bdpt image: each mutation together with the bidirectional mutation
// (needed for ergodicity), and all of them, on small scenes that exercise the moves -- the diffuse
// Cornell box, the box with a glass and a mirror sphere (caustics on the floor, the box seen through
// glass), that box through a thin lens, and boxes lit by a point or a spot light (delta-position light
// vertices; with the glass sphere, caustics from them). Compared: the image mean and 4 x 4 tile means (luminance),
// veach-mlt over kRuns independent job seeds (through plan -> run every chain -> merge -> develop,
// common/methods/veach/veach_job.h; its spread gives the standard error, b's included) against bdpt over
// independent pixel samples. Pass: every |difference| below kZ combined standard errors (17 comparisons,
// 16 runs: t with 15 dof, P(|t| > 4.5) = 4e-4 each).
// A chain with a deliberately wrong transition ratio (the bidirectional mutation's T-ratio forced to 1)
// must fail the same comparison, so the test can tell. Scenes are rendered at max depth 4-5: with the
// mirror and depth 6, glass caustics seen in the mirror made single runs heavy-tailed.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/integrators/evaluators.h"
#include "common/methods/veach/veach_chain.h"
#include "common/methods/veach/veach_job.h"
#include "common/mlt/develop.h"
#include "common/mlt/kelemen_source.h"
#include "common/mlt/pss_chain.h"
#include "common/render/render_scene.h"
#include "tests/support/estimates.h"
#include "tests/support/test_scenes.h"
#include "tests/support/veach_stats.h"

namespace mlt {
namespace {

using veach::MutationSettings;

constexpr int kRuns = 16, kTiles = 4, kSize = 16;
constexpr double kZ = 4.5;

test::ImageStats bdptStats(const RenderScene& scene, int maxDepth, uint64_t samplesPerPixel) {
  IntegratorSettings is;
  is.maxDepth = maxDepth;
  const BdptEvaluator bdpt(scene, is);
  return test::estimateImage(bdpt, kSize, kSize, 77, samplesPerPixel * kSize * kSize, kTiles, kTiles);
}

// The box with the glass sphere alone (the mirror sphere removed): a caustic on the floor, the box seen
// through glass. With the mirror, paths like a glass caustic seen in the mirror (found only when the eye
// subpath hits the light) make single runs heavy-tailed in some tiles (one tile varied 5x between runs):
// correct on average (80 runs: 1.4 sigma from bdpt) but beyond what 16 runs' spread can test.
SceneDesc glassBox() {
  SceneDesc d = test::cornellBoxSpecular(kSize, kSize);
  std::erase_if(d.meshes, [](const MeshDesc& m) { return m.name == "mirror sphere"; });
  return d;
}

// The diffuse box with a mirror for its back wall: the camera sees the box in the mirror (E S D ...) and
// light reaches surfaces by way of the mirror (... D S L), so paths E S D S L, the multi-chain
// perturbation's, are common.
SceneDesc mirrorWallBox() {
  SceneDesc d = test::smallCornellBox(kSize, kSize);
  BsdfDesc mirror;
  mirror.type = BsdfDesc::Type::Conductor;
  mirror.id = "mirror wall";
  mirror.mirror = true;
  d.bsdfs.push_back(mirror);
  for (MeshDesc& m : d.meshes)
    if (m.name == "back") m.bsdf = int(d.bsdfs.size()) - 1;
  return d;
}

MutationSettings only(std::initializer_list<int> kinds) {
  MutationSettings m;
  for (double& w : m.weight) w = 0;
  for (int k : kinds) m.weight[k] = 1;
  return m;
}

double compare(const char* name, const RenderScene& scene, int maxDepth, const MutationSettings& mut, double mpp,
               const test::ImageStats& ref) {
  std::string acc;
  RenderSettings s;
  s.width = s.height = kSize;
  s.integrator.maxDepth = maxDepth;
  s.mutationsPerPixel = mpp;
  s.chains = 8;  // long chains (~2-3k mutations): a wrong acceptance ratio shows before the start states wash it out
  s.params["veach-light-view"] = std::to_string(mut.lightView);  // the plan's bootstrap and the chains agree
  const test::ImageStats st = test::veachStats(scene, s, mut, kRuns, kTiles, 4000, &acc);
  int where = 0;
  const double z = test::maxZ(st, ref, &where);
  if (getenv("VEACH_DEBUG"))
    for (size_t e = 0; e < st.mean.size(); ++e)
      std::printf("  entry %zu: %.5f +- %.5f vs bdpt %.5f +- %.5f\n", e, st.mean[e], st.stdErr[e], ref.mean[e], ref.stdErr[e]);
  std::printf("%s: mean %.5f +- %.5f (bdpt %.5f +- %.5f), max z %.2f at %d; acceptance: %s\n", name, st.mean[0],
              st.stdErr[0], ref.mean[0], ref.stdErr[0], z, where, acc.c_str());
  return z;
}

// The same chains with the bidirectional mutation's T-ratio replaced by 1 (as if it were symmetric).
class SymmetricBidir final : public ChainState {
 public:
  explicit SymmetricBidir(veach::VeachChainState& s) : s_(s) {}
  Proposal propose() override {
    Proposal p = s_.propose();
    if (p.kind == veach::kBidir && p.tRatio > 0) p.tRatio = 1;
    return p;
  }
  void accept() override { s_.accept(); }
  void reject() override { s_.reject(); }

 private:
  veach::VeachChainState& s_;
};

test::ImageStats wrongStats(const RenderScene& scene, int maxDepth, double mpp) {
  std::vector<std::vector<double>> values;
  for (int r = 0; r < kRuns; ++r) {
    RenderSettings s;
    s.seed = 4000 + uint64_t(r);
    s.width = s.height = kSize;
    s.integrator.maxDepth = maxDepth;
    s.mutationsPerPixel = mpp;
    s.chains = 8;
    s.params["veach-light-view"] = "0";  // the chains carry every path (this space has them all)
    const JobPlan plan = veach::planVeachJob(scene, s);
    const veach::PathSpace space(scene, maxDepth);
    Film film(kSize, kSize);
    for (const WorkUnit& u : plan.units) {
      IndependentSource src = IndependentSource::candidate(s.seed, u.startCandidate);
      const auto sp = veach::startPathFromSample(space, s.integrator, src, 0.5);
      if (!sp) continue;
      veach::VeachChainState state(space, only({veach::kBidir}), sp->path, chainRng(s.seed, u.index, 4));
      SymmetricBidir wrong(state);
      veach::VeachChainTarget target(state);
      PathContribution current, scratch;
      veach::currentContribution(state, current);
      FilmSink sink(film, chainLayer(0));
      Pcg32 acceptRng = chainRng(s.seed, u.index, 1);
      runChain(wrong, target, ChainConfig{}, sink, acceptRng, u.mutations, current, luminance(current.total()), scratch);
    }
    values.push_back(test::tileMeans(
        film.develop(std::vector<double>{0.0, chainSplatScale(plan.norm.b, plan.norm.totalMutations, kSize * kSize)}),
        kSize, kSize, kTiles));
  }
  return test::statsOverRuns(values, kTiles);
}

TEST(VeachChain, DiffuseBox) {
  const auto scene = RenderScene::build(test::smallCornellBox(kSize, kSize));
  const test::ImageStats ref = bdptStats(*scene, 5, 256);
  EXPECT_LT(compare("diffuse, bidir", *scene, 5, only({veach::kBidir}), 64, ref), kZ);
  EXPECT_LT(compare("diffuse, bidir + lens subpath", *scene, 5, only({veach::kBidir, veach::kLensSubpath}), 64, ref), kZ);
  EXPECT_LT(compare("diffuse, bidir + lens", *scene, 5, only({veach::kBidir, veach::kLens}), 64, ref), kZ);
  EXPECT_LT(compare("diffuse, bidir + caustic", *scene, 5, only({veach::kBidir, veach::kCaustic}), 64, ref), kZ);
  EXPECT_LT(compare("diffuse, bidir + deep lens", *scene, 5, only({veach::kBidir, veach::kDeepLens}), 64, ref), kZ);
  // The comparison can fail: a symmetric T-ratio for the bidirectional mutation is detected.
  const double zWrong = test::maxZ(wrongStats(*scene, 5, 64), ref);
  std::printf("diffuse, bidir with T-ratio 1: max z %.2f\n", zWrong);
  EXPECT_GT(zWrong, kZ);
}

TEST(VeachChain, GlassSphere) {
  const auto scene = RenderScene::build(glassBox());
  const test::ImageStats ref = bdptStats(*scene, 4, 512);
  EXPECT_LT(compare("glass, bidir + caustic", *scene, 4, only({veach::kBidir, veach::kCaustic}), 96, ref), kZ);
  EXPECT_LT(compare("glass, bidir + lens", *scene, 4, only({veach::kBidir, veach::kLens}), 96, ref), kZ);
  EXPECT_LT(compare("glass, bidir + lens subpath", *scene, 4, only({veach::kBidir, veach::kLensSubpath}), 96, ref), kZ);
  EXPECT_LT(compare("glass, all", *scene, 4, MutationSettings{}, 96, ref), kZ);
}

TEST(VeachChain, GlassAndMirrorSpheres) {
  const auto scene = RenderScene::build(test::cornellBoxSpecular(kSize, kSize));
  const test::ImageStats ref = bdptStats(*scene, 5, 512);
  EXPECT_LT(compare("glass + mirror, bidir + caustic", *scene, 5, only({veach::kBidir, veach::kCaustic}), 96, ref), kZ);
  EXPECT_LT(compare("glass + mirror, all", *scene, 5, MutationSettings{}, 96, ref), kZ);
  EXPECT_LT(compare("glass + mirror, bidir + deep lens", *scene, 5, only({veach::kBidir, veach::kDeepLens}), 96, ref), kZ);
  MutationSettings chainsOnly;  // no light-view pass: the chains carry the light seen directly and through glass
  chainsOnly.lightView = 0;
  EXPECT_LT(compare("glass + mirror, all, light views in the chains", *scene, 5, chainsOnly, 96, ref), kZ);
}

TEST(VeachChain, MirrorWall) {
  const auto scene = RenderScene::build(mirrorWallBox());
  const test::ImageStats ref = bdptStats(*scene, 5, 512);
  EXPECT_LT(compare("mirror wall, bidir + multichain", *scene, 5, only({veach::kBidir, veach::kMultiChain}), 96, ref), kZ);
  EXPECT_LT(compare("mirror wall, all", *scene, 5, MutationSettings{}, 96, ref), kZ);
  EXPECT_LT(compare("mirror wall, bidir + deep lens", *scene, 5, only({veach::kBidir, veach::kDeepLens}), 96, ref), kZ);
}

TEST(VeachChain, ThinLens) {
  SceneDesc desc = glassBox();
  desc.camera.type = CameraDesc::Type::ThinLens;
  desc.camera.apertureRadius = 0.15f;
  desc.camera.focusDistance = 3.0f;
  const auto scene = RenderScene::build(desc);
  const test::ImageStats ref = bdptStats(*scene, 4, 512);
  EXPECT_LT(compare("thin lens, bidir + lens", *scene, 4, only({veach::kBidir, veach::kLens}), 96, ref), kZ);
  EXPECT_LT(compare("thin lens, all", *scene, 4, MutationSettings{}, 96, ref), kZ);
  EXPECT_LT(compare("thin lens, bidir + deep lens", *scene, 4, only({veach::kBidir, veach::kDeepLens}), 96, ref), kZ);
}

// Delta-position lights (path.h): the box lit by the point light alone, by the spot light alone, and the
// glass sphere's box lit by both (caustics next to the light: the light-free run of path.h).
SceneDesc oneLight(SceneDesc d, LightDesc::Type keep) {
  std::erase_if(d.lights, [keep](const LightDesc& l) { return l.type != keep; });
  return d;
}

TEST(VeachChain, PointLight) {
  const auto scene = RenderScene::build(oneLight(test::cornellBoxPointSpot(kSize, kSize), LightDesc::Type::Point));
  ASSERT_EQ(scene->lights().size(), 1u);
  const test::ImageStats ref = bdptStats(*scene, 5, 256);
  EXPECT_LT(compare("point light, bidir", *scene, 5, only({veach::kBidir}), 64, ref), kZ);
  EXPECT_LT(compare("point light, bidir + caustic", *scene, 5, only({veach::kBidir, veach::kCaustic}), 64, ref), kZ);
  EXPECT_LT(compare("point light, bidir + deep lens", *scene, 5, only({veach::kBidir, veach::kDeepLens}), 64, ref), kZ);
  EXPECT_LT(compare("point light, all", *scene, 5, MutationSettings{}, 64, ref), kZ);
}

TEST(VeachChain, SpotLight) {
  const auto scene = RenderScene::build(oneLight(test::cornellBoxPointSpot(kSize, kSize), LightDesc::Type::Spot));
  ASSERT_EQ(scene->lights().size(), 1u);
  const test::ImageStats ref = bdptStats(*scene, 5, 256);
  EXPECT_LT(compare("spot light, bidir + caustic", *scene, 5, only({veach::kBidir, veach::kCaustic}), 64, ref), kZ);
  EXPECT_LT(compare("spot light, all", *scene, 5, MutationSettings{}, 64, ref), kZ);
}

TEST(VeachChain, GlassSphereLitByPointAndSpot) {
  SceneDesc d = test::cornellBoxSpecularPointSpot(kSize, kSize);
  std::erase_if(d.meshes, [](const MeshDesc& m) { return m.name == "mirror sphere"; });
  const auto scene = RenderScene::build(d);
  const test::ImageStats ref = bdptStats(*scene, 4, 512);
  EXPECT_LT(compare("glass, point + spot, bidir + caustic", *scene, 4, only({veach::kBidir, veach::kCaustic}), 96, ref), kZ);
  EXPECT_LT(compare("glass, point + spot, all", *scene, 4, MutationSettings{}, 96, ref), kZ);
}

}  // namespace
}  // namespace mlt
