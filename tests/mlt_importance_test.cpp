// The relative target (common/mlt/importance.h, common/job/importance_pilot.h):
//  - the map: tile sizes, (R2) from tile sums (3 x 3 pooling, the floor, the scale), lookups, validation;
//  - the target reads it: c = sum of each splat's luminance times its tile's h;
//  - a chain samples c = f h: many independent chains on a 1D film of four pixels with a map end in
//    pixel j with probability f_j h_j / sum (chi-square), and without the map f_j / sum; the two
//    distributions differ enough that each test would fail the other's;
//  - b of the relative target is what it integrates: the bootstrap's b (mmlt's b_1 from camera rays
//    included) agrees with a bdpt estimate of (1/P) sum_j h_j luminance(I_j) within their errors;
//  - the pilot is a pure function of (scene, seed, film, integrator, floor): threads and repetition
//    give the same bits, another seed another map;
//  - the methods take "target" (luminance by default), "target-floor" and "target-power", and the luminance
//    target has no map;
//  - a tempered target (common/mlt/target.h (T1)): c = (sum of luminance times h)^beta, a chain ends in pixel
//    j with probability f_j^beta / sum (chi-square, told apart from f_j), and each slot's image still holds
//    P b_lum (D8).
// The image stays unbiased with the map: MltBundled.AgreesWithBdpt (mlt_bundled_test.cpp) has a case with
// the relative target.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <vector>

#include "common/core/color.h"
#include "common/integrators/evaluators.h"
#include "common/job/importance_pilot.h"
#include "common/job/mlt_job.h"
#include "common/methods/pss_method.h"
#include "common/methods/registry.h"
#include "common/mlt/chain.h"
#include "common/mlt/importance.h"
#include "common/mlt/kelemen_source.h"
#include "common/mlt/pss_chain.h"
#include "common/mlt/target.h"
#include "common/render/render_scene.h"
#include "tests/support/chi2.h"
#include "tests/support/estimates.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

TEST(ImportanceMap, TilesKeepTheMapAtMost64PerAxis) {
  EXPECT_EQ(importanceTileSize(48, 36), 1);
  EXPECT_EQ(importanceTileSize(64, 64), 1);
  EXPECT_EQ(importanceTileSize(65, 10), 2);
  EXPECT_EQ(importanceTileSize(256, 256), 4);
  EXPECT_EQ(importanceTileSize(1920, 1080), 30);
  for (const auto& [w, h] : {std::pair{256, 256}, {1920, 1080}, {4097, 3}, {1, 1}}) {
    const int T = importanceTileSize(w, h);
    EXPECT_LE((std::max(w, h) + T - 1) / T, kImportanceMaxTiles) << w << "x" << h;
  }
}

// A 3 x 1 film: tile i's g pools its neighbours, h = 1 / sqrt(g^2 + (floor gbar)^2), scaled so that
// the mean of h g over the samples is gbar.
TEST(ImportanceMap, FollowsR2FromTheTileSums) {
  const std::vector<double> sums = {8, 2, 0};  // one sample per tile
  const double floor = 0.5, gbar = 10.0 / 3;
  const double g[3] = {5, 10.0 / 3, 1};
  double h[3], hg = 0;
  for (int i = 0; i < 3; ++i) {
    h[i] = 1 / std::sqrt(g[i] * g[i] + floor * floor * gbar * gbar);
    hg += h[i] * g[i];
  }
  const double scale = gbar * 3 / hg;
  const ImportanceMap m = importanceFromTileSums(3, 1, sums, {1, 1, 1}, floor);
  ASSERT_EQ(m.h.size(), 3u);
  EXPECT_EQ(m.tileSize, 1);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(m.h[i], h[i] * scale, 1e-6 * h[i] * scale) << i;
  EXPECT_GT(m.h[2], m.h[1]);  // darker: more weight
  EXPECT_GT(m.h[1], m.h[0]);
  // Nothing seen: no map (the luminance target). Bad input: an error naming it.
  EXPECT_TRUE(importanceFromTileSums(3, 1, {0, 0, 0}, {1, 1, 1}, floor).empty());
  EXPECT_THROW(importanceFromTileSums(3, 1, sums, {1, 1, 1}, 0), std::invalid_argument);
  EXPECT_THROW(importanceFromTileSums(3, 1, sums, {1, 1}, floor), std::invalid_argument);
  EXPECT_THROW(importanceFromTileSums(0, 1, sums, {1, 1, 1}, floor), std::invalid_argument);
}

TEST(ImportanceMap, LookupsAndValidation) {
  std::vector<double> sums(44 * 3);
  for (size_t i = 0; i < sums.size(); ++i) sums[i] = double(i % 5) * 21;
  const ImportanceMap m = importanceFromTileSums(130, 7, sums, std::vector<uint64_t>(sums.size(), 21), 0.25);
  ASSERT_EQ(m.h.size(), 44u * 3u);
  EXPECT_EQ(m.at(Vec2(0.5f, 0.5f)), m.h[0]);
  EXPECT_EQ(m.at(Vec2(5.9f, 2.0f)), m.h[1]);       // x 5 -> tile 1
  EXPECT_EQ(m.at(Vec2(129.9f, 6.9f)), m.h[2 * 44 + 43]);
  EXPECT_EQ(m.at(Vec2(-3.0f, 100.0f)), m.h[2 * 44]);  // clamped to the film
  EXPECT_NO_THROW(validateImportanceMap(m, "map"));
  EXPECT_NO_THROW(validateImportanceMap(ImportanceMap{}, "map"));  // empty: no map
  ImportanceMap bad = m;
  bad.h[7] = std::numeric_limits<float>::infinity();
  EXPECT_THROW(validateImportanceMap(bad, "map"), std::invalid_argument);
  bad = m;
  bad.h.pop_back();
  EXPECT_THROW(validateImportanceMap(bad, "map"), std::invalid_argument);
  bad = m;
  bad.tileSize = 4;
  EXPECT_THROW(validateImportanceMap(bad, "map"), std::invalid_argument);
  try {
    bad.h[0] = -1;
    bad.tileSize = m.tileSize;
    validateImportanceMap(bad, "plan.norm.importance");
    ADD_FAILURE() << "a negative h was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("plan.norm.importance"), std::string::npos) << e.what();
  }
}

// A map over a film of `h.size()` x 1 pixels, one tile per pixel.
ImportanceMap rowMap(const std::vector<float>& h) {
  ImportanceMap m;
  m.filmWidth = int(h.size());
  m.filmHeight = 1;
  m.tileSize = 1;
  m.tilesX = int(h.size());
  m.tilesY = 1;
  m.h = h;
  return m;
}

TEST(ImportanceTarget, WeightsEachSplatByItsTile) {
  const ImportanceMap m = rowMap({0.5f, 2.0f, 4.0f});
  PathContribution p;
  p.splats.push_back({Vec2(0.2f, 0.5f), Color(1.0f)});
  p.splats.push_back({Vec2(2.7f, 0.5f), Color(0.25f, 0.5f, 1.0f)});
  const double c = double(luminance(Color(1.0f))) * 0.5 + double(luminance(Color(0.25f, 0.5f, 1.0f))) * 4.0;
  EXPECT_NEAR(targetFunction(p, TargetShape{&m}), c, 1e-12);
  EXPECT_EQ(targetFunction(p, TargetShape{nullptr}), targetFunction(p));  // no map: the luminance of the total
  const ImportanceMap none;
  EXPECT_EQ(targetFunction(p, TargetShape{&none}), targetFunction(p));
  p.splats[0].L = Color(-100.0f);  // a negative total is no valid target
  EXPECT_EQ(targetFunction(p, TargetShape{&m}), 0.0);
}

TEST(TemperedTarget, RaisesTheWeightedSumToItsPower) {
  const ImportanceMap m = rowMap({0.5f, 2.0f, 4.0f});
  PathContribution p;
  p.splats.push_back({Vec2(0.2f, 0.5f), Color(1.0f)});
  p.splats.push_back({Vec2(2.7f, 0.5f), Color(0.25f, 0.5f, 1.0f)});
  const double lum = targetFunction(p), weighted = targetFunction(p, TargetShape{&m});
  EXPECT_NEAR(targetFunction(p, TargetShape{nullptr, 0.5}), std::sqrt(lum), 1e-12);
  EXPECT_NEAR(targetFunction(p, TargetShape{&m, 0.7}), std::pow(weighted, 0.7), 1e-12);
  EXPECT_EQ(targetFunction(p, TargetShape{&m, 1}), weighted);  // power 1: the same bits
  EXPECT_EQ(targetFunction(p, TargetShape{}), lum);
  EXPECT_FALSE(TargetShape{}.shaped());
  EXPECT_TRUE((TargetShape{nullptr, 0.5}.shaped()));
  EXPECT_TRUE((TargetShape{&m, 1}.shaped()));
  const ImportanceMap none;
  EXPECT_FALSE((TargetShape{&none, 1}.shaped()));
  p.splats[0].L = Color(-100.0f);
  EXPECT_EQ(targetFunction(p, TargetShape{nullptr, 0.5}), 0.0);
}

// ---- a chain samples c = f h ----------------------------------------------------------------------
constexpr uint64_t kSeed = 20261206;
const double kF[4] = {10, 1, 3, 0.5};        // f per pixel of a 4 x 1 film
const std::vector<float> kH = {0.1f, 1.0f, 0.5f, 2.0f};  // c = f h: 1, 1, 1.5, 1

class PixelTarget final : public ChainTarget {  // x from the camera stream, f constant over each pixel
 public:
  explicit PixelTarget(SampleSource& source) : source_(source) {}
  void evaluate(PathContribution& out) override {
    source_.startStream(Stream::Camera);
    const float x = 4 * source_.next1D();
    out.splats.push_back({Vec2(x, 0.5f), Color(float(kF[std::min(3, int(x))]))});
  }

 private:
  SampleSource& source_;
};

class NullSink final : public ChainSink {
 public:
  void splat(const PathContribution&, double) override {}
};

// Final pixels of `chains` independent chains of `mutations` steps, each from a uniform start.
std::vector<int> finalPixels(const TargetShape& shape, int chains, uint64_t mutations) {
  KelemenParams params;
  params.largeStepProb = 0.3f;
  std::vector<int> pixels;
  PathContribution current, scratch;
  NullSink sink;
  ChainConfig config;
  config.target = shape;
  for (int j = 0; j < chains; ++j) {
    KelemenSource source(params, kSeed, uint64_t(j), uint64_t(j));
    PixelTarget target(source);
    current.clear();
    target.evaluate(current);
    source.accept();
    PssState state(source);
    Pcg32 acceptRng = chainRng(kSeed, uint64_t(j), 1);
    runChain(state, target, config, sink, acceptRng, mutations, current, targetFunction(current, shape), scratch);
    pixels.push_back(std::min(3, int(current.splats[0].pRaster.x)));
  }
  return pixels;
}

// Chi-square p-value of pixel counts against probabilities proportional to w (3 degrees of freedom).
double pValue(const std::vector<int>& pixels, const double (&w)[4]) {
  double counts[4] = {}, total = 0;
  for (int p : pixels) counts[p] += 1;
  for (double v : w) total += v;
  double stat = 0;
  for (int i = 0; i < 4; ++i) {
    const double e = double(pixels.size()) * w[i] / total;
    stat += (counts[i] - e) * (counts[i] - e) / e;
  }
  return test::chi2SurvivalProbability(stat, 3);
}

TEST(ImportanceTarget, AChainVisitsPixelsInProportionToFTimesH) {
  const ImportanceMap map = rowMap(kH);
  double fh[4], f[4];
  for (int i = 0; i < 4; ++i) {
    f[i] = kF[i] * double(luminance(Color(1.0f)));
    fh[i] = f[i] * double(kH[i]);
  }
  const std::vector<int> relative = finalPixels(TargetShape{&map}, 4000, 64);
  const std::vector<int> plain = finalPixels(TargetShape{}, 4000, 64);
  const double pRelative = pValue(relative, fh), pPlain = pValue(plain, f);
  std::printf("with the map: p = %.3g against f h (%.3g against f); without: p = %.3g against f\n", pRelative,
              pValue(relative, f), pPlain);
  EXPECT_GT(pRelative, 1e-3);
  EXPECT_GT(pPlain, 1e-3);
  EXPECT_LT(pValue(relative, f), 1e-9);  // the test tells the two apart
  EXPECT_LT(pValue(plain, fh), 1e-9);
}

TEST(TemperedTarget, AChainVisitsPixelsInProportionToFToTheBeta) {
  constexpr double kBeta = 0.5;
  double fb[4], f[4];
  for (int i = 0; i < 4; ++i) {
    f[i] = kF[i] * double(luminance(Color(1.0f)));
    fb[i] = std::pow(f[i], kBeta);
  }
  const std::vector<int> tempered = finalPixels(TargetShape{nullptr, kBeta}, 4000, 64);
  const double p = pValue(tempered, fb);
  std::printf("tempered (beta %.1f): p = %.3g against f^beta (%.3g against f)\n", kBeta, p, pValue(tempered, f));
  EXPECT_GT(p, 1e-3);
  EXPECT_LT(pValue(tempered, f), 1e-9);  // the test tells f^beta from f
}

// ---- b of the relative target ---------------------------------------------------------------------
constexpr int kW = 32, kH2 = 24;

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(kW, kH2));
  return *scene;
}

RenderSettings chainSettings(const char* method, uint64_t seed) {
  RenderSettings s;
  s.directLight = DirectLight::Chains;
  s.method = method;
  s.seed = seed;
  s.width = kW;
  s.height = kH2;
  s.integrator.maxDepth = 4;
  s.mutationsPerPixel = 64;
  s.bootstrapSamples = 1 << 16;
  s.params["target"] = "relative";
  return s;
}

class RelativeB : public ::testing::TestWithParam<const char*> {};

// E[c] = (1/P) sum_j h_j luminance(I_j): bdpt samples with every splat weighted by its tile's h estimate it.
TEST_P(RelativeB, TheBootstrapsBIsTheHWeightedImageMean) {
  const RenderSettings s = chainSettings(GetParam(), 11);
  const MarkovChainBootstrap boot = bootstrapMarkovChainJob(cornell(), s);
  ASSERT_TRUE(boot.importance);
  const ImportanceMap& map = boot.importance->map;
  ASSERT_FALSE(map.empty());
  EXPECT_EQ(map.tileSize, 1);
  const auto bdpt = makeEvaluator(cornell(), "bdpt", s.integrator);
  const test::ImageStats weighted = test::estimateImageFrom(
      [&](uint64_t i, PathContribution& out) {
        IndependentSource source(777, i);
        const Vec2 pixel{float(i % uint64_t(kW)), float(i / uint64_t(kW) % uint64_t(kH2))};
        bdpt->evaluate(source, &pixel, out);
        for (Splat& sp : out.splats) sp.L = sp.L * map.at(sp.pRaster);
      },
      kW, kH2, uint64_t(kW) * kH2 * 512, 1, 1, -1, uint64_t(kW) * kH2);
  const double z = (boot.result.b - weighted.mean[0]) / std::hypot(boot.result.bStdErr, weighted.stdErr[0]);
  std::printf("%s: bootstrap b = %.6g +- %.2g, bdpt's h-weighted mean %.6g +- %.2g, z = %.2f\n", GetParam(),
              boot.result.b, boot.result.bStdErr, weighted.mean[0], weighted.stdErr[0], z);
  EXPECT_LT(std::fabs(z), 4.0);
  EXPECT_LT(4 * std::hypot(boot.result.bStdErr, weighted.stdErr[0]), 0.03 * weighted.mean[0]) << "test too weak";
}

INSTANTIATE_TEST_SUITE_P(Methods, RelativeB, ::testing::Values("pssmlt", "mmlt"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

// (D8): with a relative or a tempered target each slot's developed image holds P b_lum^ of luminance,
// b_lum^ pooled from the bootstrap's luminance and the large steps' (refinedLuminanceB), whatever the chains'
// spread; and the farm's partials carry the large steps' luminance sums.
TEST(ShapedDevelop, EachSlotsImageHoldsBLuminance) {
  struct Shape {
    const char* target;
    const char* power;
  };
  for (const Shape shape : {Shape{"relative", "1"}, Shape{"luminance", "0.6"}})
  for (const char* method : {"pssmlt", "mmlt"}) {
    RenderSettings s = chainSettings(method, 3);
    s.params["target"] = shape.target;
    s.params["target-power"] = shape.power;
    s.mutationsPerPixel = 16;
    s.bootstrapSamples = 4096;
    const JobPlan plan = planJob(cornell(), s);
    ASSERT_TRUE(plan.norm.target().shaped()) << shape.target;
    EXPECT_EQ(plan.norm.importance.empty(), std::string(shape.target) == "luminance");
    EXPECT_EQ(plan.norm.targetPower, std::stod(shape.power));
    ASSERT_EQ(plan.norm.bootstrapLuminance.size(), plan.norm.mutationsPerLength.size());
    PartialResult merged;
    for (const WorkUnit& u : plan.units) merged.add(runWorkUnit(cornell(), plan, u));
    const RefinedB lum = refinedLuminanceB(plan.norm, merged.stats);
    uint64_t largeSteps = 0;
    for (const TargetSums& t : merged.stats.largeStepLuminanceSums) largeSteps += t.n;
    EXPECT_GT(largeSteps, 0u) << method;
    // Slot by slot: develop with every other slot's scale set to 0.
    const std::vector<double> scales = markovChainLayerScales(plan, merged);
    double total = 0;
    for (size_t slot = 0; slot < plan.norm.mutationsPerLength.size(); ++slot) {
      if (plan.norm.mutationsPerLength[slot] == 0) continue;
      std::vector<double> only(scales.size(), 0.0);
      for (size_t layer : {chainLayer(slot), largeStepLayer(slot, plan.norm.mutationsPerLength.size())})
        if (layer < only.size()) only[layer] = scales[layer];
      double sum = 0;
      for (const Color& c : merged.film.develop(only)) sum += double(luminance(c));
      EXPECT_NEAR(sum, lum.perSlot[slot].b * kW * kH2, 1e-5 * sum) << method << " slot " << slot;
      total += sum;
    }
    double image = 0;
    for (const Color& c : developImage(plan, merged)) image += double(luminance(c));
    EXPECT_NEAR(image, total, 1e-5 * image) << method;
    EXPECT_NEAR(image / (kW * kH2), lum.total.b, 1e-5 * lum.total.b) << method;
  }
}

TEST(ImportancePilot, IsAPureFunctionOfItsInputs) {
  const RenderSettings s = chainSettings("mmlt", 5);
  const ImportancePilot a = importancePilot(cornell(), s, 0.5, true);
  const ImportancePilot b = importancePilot(cornell(), s, 0.5, false);
  EXPECT_EQ(a.map, b.map);
  EXPECT_EQ(a.cost, b.cost);
  EXPECT_EQ(a.samples, uint64_t(kW) * kH2 * 29);  // T = 1: ceil(256 / 9) samples per pixel
  EXPECT_EQ(importancePilot(cornell(), s, 0.5).map, a.map);
  EXPECT_NE(importancePilot(cornell(), chainSettings("mmlt", 6), 0.5).map, a.map);
  EXPECT_NE(importancePilot(cornell(), s, 2.0).map, a.map);
}

TEST(ImportancePilot, TheMethodsTakeTheTargetItsFloorAndItsPower) {
  for (const char* name : {"pssmlt", "pssmlt-bdpt", "mmlt", "rjmlt"}) {
    const ChainJobSpec* spec = findChainJobSpec(name);
    ASSERT_NE(spec, nullptr) << name;
    RenderSettings s = chainSettings(name, 1);
    EXPECT_EQ(spec->importanceFloor(s), std::stod(kDefaultTargetFloor)) << name;
    s.params.erase("target");  // the default: luminance
    EXPECT_EQ(spec->importanceFloor(s), 0.0) << name;
    s.params["target"] = "relative";
    s.params["target-floor"] = "2";
    EXPECT_EQ(spec->importanceFloor(s), 2.0) << name;
    s.params["target"] = "luminance";
    EXPECT_EQ(spec->importanceFloor(s), 0.0) << name;
    EXPECT_FALSE(bootstrapMarkovChainJob(cornell(), s).importance) << name;  // no pilot, no map
    s.params["target"] = "brightness";
    EXPECT_THROW(findMethod(name).validate(s), std::invalid_argument) << name;
    s.params["target"] = "luminance";
    EXPECT_EQ(spec->targetPower(s), 1.0) << name;  // the default
    s.params["target-power"] = "0.7";
    EXPECT_EQ(spec->targetPower(s), 0.7) << name;
    EXPECT_NO_THROW(findMethod(name).validate(s)) << name;
    for (const char* bad : {"0", "0.01", "1.5", "-1", "nan"}) {
      s.params["target-power"] = bad;
      EXPECT_THROW(findMethod(name).validate(s), std::invalid_argument) << name << " " << bad;
    }
  }
  EXPECT_EQ(findChainJobSpec("veach-mlt")->importanceFloor(chainSettings("veach-mlt", 1)), 0.0);
  EXPECT_EQ(findChainJobSpec("veach-mlt")->targetPower(chainSettings("veach-mlt", 1)), 1.0);
  // A plan takes a bootstrap of its own target only: c differs with the power.
  RenderSettings s = chainSettings("mmlt", 2);
  s.params["target"] = "luminance";
  s.params["target-power"] = "0.7";
  const MarkovChainBootstrap boot = bootstrapMarkovChainJob(cornell(), s);
  EXPECT_NO_THROW(planMarkovChainJob(cornell(), s, boot));
  s.params["target-power"] = "1";
  try {
    planMarkovChainJob(cornell(), s, boot);
    ADD_FAILURE() << "a bootstrap of another power was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the target's power"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mlt
