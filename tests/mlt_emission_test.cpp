// b_1 from camera rays (common/job/emission_estimate.h): the per-length methods' b_1 (the emission seen
// directly) estimated pixel by pixel instead of by the bootstrap's candidates.
//  - (E1): it estimates what the chains' target c_1 integrates to: i.i.d. uniform samples of mmlt's target
//    of length 1 (every technique, the light-tracing one included) agree with it within their error;
//  - unbiased, and its stated standard error is what its run-to-run spread is: 40 seeds against i.i.d.
//    uniform camera rays;
//  - far more precise than the candidates at a fraction of their count per unit of error;
//  - a pure function of (scene, seed): thread count and repetition give the same bits;
//  - wired into mmlt's and rjmlt's bootstrap (slot 1, no tail split; length 1's candidates then only seed
//    chains and are not grown, but a light they all missed still gets some), not into the one-length
//    methods'.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "common/core/color.h"
#include "common/integrators/evaluators.h"
#include "common/job/emission_estimate.h"
#include "common/job/mlt_job.h"
#include "common/methods/pss_method.h"
#include "common/methods/registry.h"
#include "common/mlt/target.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"
#include "common/scene/mitsuba_loader.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

constexpr int kW = 48, kH = 36;

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(kW, kH));
  return *scene;
}

RenderSettings settings(const char* method, uint64_t seed) {
  RenderSettings s;
  s.directLight = DirectLight::Chains;  // chains over every length (the automatic choice: direct_light_rule_test)
  s.method = method;
  s.seed = seed;
  s.width = kW;
  s.height = kH;
  s.integrator.maxDepth = 4;
  s.mutationsPerPixel = 4;
  s.bootstrapSamples = 4096;
  return s;
}

// scenes/<name>.xml on a res x res film, and mmlt's settings for it.
std::unique_ptr<RenderScene> bundledScene(const std::string& name, int res) {
  SceneDesc desc = loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + name + ".xml");
  desc.camera.width = desc.camera.height = res;
  return RenderScene::build(desc);
}
RenderSettings squareSettings(uint64_t seed, int res) {
  RenderSettings s = settings("mmlt", seed);
  s.width = s.height = res;
  return s;
}

struct Mean {
  double mean = 0, stdErr = 0;
};

// i.i.d. samples of f(i): their mean and its standard error.
template <typename F>
Mean iidMean(uint64_t n, F f) {
  double sum = 0, sumSq = 0;
  for (uint64_t i = 0; i < n; ++i) {
    const double v = f(i);
    sum += v;
    sumSq += v * v;
  }
  const double m = sum / double(n);
  return {m, std::sqrt(std::max(0.0, (sumSq - double(n) * m * m) / double(n - 1)) / double(n))};
}

// b_1 by plain Monte Carlo: uniform camera rays over the film, pt limited to one segment.
Mean plainEmission(uint64_t n, uint64_t seed, const RenderScene& scene = cornell()) {
  IntegratorSettings one;
  one.maxDepth = 1;
  const std::unique_ptr<PathEvaluator> pt = makeEvaluator(scene, "pt", one);
  PathContribution path;
  return iidMean(n, [&](uint64_t i) {
    IndependentSource source(seed, i);
    path.clear();
    pt->evaluate(source, nullptr, path);
    return targetFunction(path);
  });
}

// The estimate over seeds 1..n: the mean of b_1, its spread (sample standard deviation) and the rms of the
// stated standard errors; check(e, seed) sees every estimate.
struct OverSeeds {
  double mean = 0, spread = 0, statedSe = 0;
};
template <typename Estimate, typename Check>
OverSeeds overSeeds(int n, Estimate estimate, Check check) {
  double sum = 0, sumSq = 0, stated = 0;
  for (int seed = 1; seed <= n; ++seed) {
    const EmissionEstimate e = estimate(uint64_t(seed));
    check(e, seed);
    sum += e.estimate.b;
    sumSq += e.estimate.b * e.estimate.b;
    stated += e.estimate.stdErr * e.estimate.stdErr;
  }
  OverSeeds o;
  o.mean = sum / n;
  o.spread = std::sqrt(std::max(0.0, (sumSq - n * o.mean * o.mean) / (n - 1)));
  o.statedSe = std::sqrt(stated / n);
  return o;
}

TEST(EmissionEstimate, EstimatesWhatTheChainsTargetOfLengthOneIntegratesTo) {
  // (E1): mmlt's c_1 over uniform primary samples (technique chosen at random, MIS-weighted).
  const ChainJobSpec* mmlt = findChainJobSpec("mmlt");
  ASSERT_TRUE(mmlt);
  const RenderSettings s = settings("mmlt", 1);
  const std::unique_ptr<PssTarget> target = mmlt->makeTarget(cornell(), s);
  PathContribution path;
  const Mean c1 = iidMean(2000000, [&](uint64_t i) {
    IndependentSource source(77, i);
    target->evaluate(source, 1, path);
    return targetFunction(path);
  });
  const EmissionEstimate e = emissionEstimate(cornell(), s);
  ASSERT_GT(e.estimate.b, 0);
  const double tol = 4 * std::hypot(c1.stdErr, e.estimate.stdErr);
  EXPECT_NEAR(e.estimate.b, c1.mean, tol) << "c_1's mean " << c1.mean << " +- " << c1.stdErr;
  EXPECT_LT(c1.stdErr / c1.mean, 0.01) << "the check must be able to fail";
}

// (T1): with a tempered target the rays estimate what c_1 = luminance(L_e)^beta integrates to, and their
// luminance summary (b_lum's, develop.h (D8)) is the plain estimate, bit for bit.
TEST(EmissionEstimate, EstimatesATemperedTargetOfLengthOne) {
  const ChainJobSpec* mmlt = findChainJobSpec("mmlt");
  ASSERT_TRUE(mmlt);
  const RenderSettings s = settings("mmlt", 1);
  const TargetShape tempered{nullptr, 0.5};
  const std::unique_ptr<PssTarget> target = mmlt->makeTarget(cornell(), s);
  PathContribution path;
  const Mean c1 = iidMean(2000000, [&](uint64_t i) {
    IndependentSource source(77, i);
    target->evaluate(source, 1, path);
    return targetFunction(path, tempered);
  });
  const EmissionEstimate e = emissionEstimate(cornell(), s, tempered);
  const EmissionEstimate plain = emissionEstimate(cornell(), s);
  ASSERT_GT(e.estimate.b, 0);
  const double tol = 4 * std::hypot(c1.stdErr, e.estimate.stdErr);
  EXPECT_NEAR(e.estimate.b, c1.mean, tol) << "c_1's mean " << c1.mean << " +- " << c1.stdErr;
  EXPECT_GT(std::fabs(plain.estimate.b - c1.mean), 10 * tol) << "the check must tell the two targets apart";
  EXPECT_EQ(e.luminance.b, plain.estimate.b);
  EXPECT_EQ(e.luminance.stdErr, plain.estimate.stdErr);
  EXPECT_EQ(plain.luminance.n, 0u);  // no summary of its own without a shaped target
}

TEST(EmissionEstimate, UnbiasedWithTheStatedStandardError) {
  const Mean reference = plainEmission(2000000, 5);
  constexpr int kSeeds = 40;
  const auto [mean, spread, statedSe] = overSeeds(
      kSeeds, [](uint64_t seed) { return emissionEstimate(cornell(), settings("mmlt", seed)); },
      [](const EmissionEstimate&, int) {});
  // Unbiased: the mean of 40 runs within 4 standard errors of the plain estimate.
  EXPECT_NEAR(mean, reference.mean, 4 * std::hypot(reference.stdErr, spread / std::sqrt(double(kSeeds))))
      << "plain " << reference.mean << " +- " << reference.stdErr;
  // The stated error is what the runs spread by (replicates: an unbiased variance estimate); 40 runs pin
  // the spread to +-11% (1 sigma), so 3 sigma either way.
  EXPECT_GT(statedSe, 0.67 * spread) << "spread " << spread << " stated " << statedSe;
  EXPECT_LT(statedSe, 1.4 * spread) << "spread " << spread << " stated " << statedSe;
  // And it is precise: the same number of plain rays would spread several times more.
  const EmissionEstimate one = emissionEstimate(cornell(), settings("mmlt", 1));
  const Mean plainSameRays = plainEmission(one.rays, 9);
  EXPECT_LT(4 * spread, plainSameRays.stdErr) << "rays " << one.rays;
}

TEST(EmissionEstimate, SpendsItsRaysOnTheLightsOutline) {
  const EmissionEstimate e = emissionEstimate(cornell(), settings("mmlt", 3));
  ASSERT_TRUE(e.estimated);
  // A 48 x 36 film has fewer than kEmissionMinCells pixels: 7 x 7 cells per pixel (6 x 6 would be fewer).
  ASSERT_EQ(e.cellsPerPixelAxis, 7);
  const uint64_t C = uint64_t(kW) * kH * 49;
  EXPECT_LT(uint64_t(kW) * kH * 36, kEmissionMinCells);
  EXPECT_GE(C, kEmissionMinCells);
  EXPECT_GT(e.edgeCells, 0u);
  EXPECT_LT(e.edgeCells, C / 4);  // the light is a small part of the film
  EXPECT_EQ(e.rays, C + (C - e.edgeCells) * kEmissionFlatRays + e.edgeCells * e.edgeRays);
  EXPECT_LE(double(e.edgeCells) * e.edgeRays, kEmissionEdgeBudget * double(C) + 1e-9);
  EXPECT_GE(e.edgeRays, kEmissionFlatRays);
  // No tail split; c_1's variance per uniform sample is the caller's.
  EXPECT_EQ(e.estimate.tau, std::numeric_limits<double>::infinity());
  EXPECT_EQ(e.estimate.bulkB, e.estimate.b);
  EXPECT_EQ(e.estimate.sampleVar, 0.0);
  EXPECT_EQ(e.estimate.bulkVar, 0.0);
}

TEST(EmissionEstimate, SameSeedSameBitsForAnyThreadCount) {
  const RenderSettings s = settings("mmlt", 4);
  const EmissionEstimate a = emissionEstimate(cornell(), s, {}, true);
  const EmissionEstimate b = emissionEstimate(cornell(), s, {}, false);
  EXPECT_EQ(std::memcmp(&a.estimate.b, &b.estimate.b, sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(&a.estimate.stdErr, &b.estimate.stdErr, sizeof(double)), 0);
  EXPECT_EQ(a.rays, b.rays);
  EXPECT_NE(emissionEstimate(cornell(), settings("mmlt", 5)).estimate.b, a.estimate.b);
}

TEST(EmissionEstimate, PerLengthMethodsTakeTheirBOneFromIt) {
  for (const char* m : {"mmlt", "rjmlt"}) {
    const ChainJobSpec* spec = findChainJobSpec(m);
    ASSERT_TRUE(spec) << m;
    RenderSettings s = settings(m, 6);
    // The budget also pays for b_1's camera rays (BootstrapConfig::spentCost: ~250 k rays at 3 units
    // each, at least kEmissionMinCells cells whatever the film): large enough that some of it is left.
    s.bootstrapSamples = 65536;
    const MarkovChainBootstrap boot = bootstrapMarkovChainJob(*spec, cornell(), s);
    ASSERT_FALSE(boot.result.lengths.empty());
    const LengthBootstrap& l1 = boot.result.lengths.front();
    ASSERT_EQ(l1.pathLength, 1) << m;
    // Length 1's candidates only seed chains: the budget grows the others, never it (seedOnlyLengths).
    EXPECT_EQ(l1.c.size(), uint64_t(s.bootstrapSamples) / 4) << m;
    EXPECT_GT(boot.result.candidates, uint64_t(s.bootstrapSamples) * boot.result.lengths.size() / 4) << m;
    EmissionEstimate e = emissionEstimate(cornell(), s);
    e.estimate.sampleVar = e.estimate.bulkVar = l1.estimate.sampleVar;  // as the bootstrap sets it
    EXPECT_EQ(l1.estimate, e.estimate) << m;
    double b = 0;
    for (const LengthBootstrap& lb : boot.result.lengths) b += lb.estimate.b;
    EXPECT_NEAR(boot.result.b, b, 1e-12 * b) << m;
    // The plan carries it to the chains: slot 1 without a tail threshold.
    const JobPlan plan = planMarkovChainJob(*spec, cornell(), s, boot);
    ASSERT_GT(plan.norm.bootstrapB.size(), 1u);
    EXPECT_EQ(plan.norm.bootstrapB[1], e.estimate) << m;
    EXPECT_EQ(plan.norm.tailThreshold(1), std::numeric_limits<double>::infinity()) << m;
  }
  // One-length methods have no length 1 of their own: their bootstrap is the candidates'.
  const ChainJobSpec* pss = findChainJobSpec("pssmlt-bdpt");
  ASSERT_TRUE(pss);
  const MarkovChainBootstrap boot = bootstrapMarkovChainJob(*pss, cornell(), settings("pssmlt-bdpt", 6));
  ASSERT_EQ(boot.result.lengths.size(), 1u);
  EXPECT_EQ(boot.result.lengths[0].estimate.n, boot.result.lengths[0].c.size());
}

// A light about a pixel wide and very bright is what the pilot reads worst (a ray hits it or not), so the
// lights' geometry marks their cells (smallLightCells): glossy-plates' spheres of equal power (radius 0.03 to
// 0.9, radiance 1/r^2; at 64x64 with 4x4 cells per pixel the cells are 256x256's pixels) all but the largest
// are small, and each holds a quarter of b_1. With the marks the rays estimate b_1 (before them the pilot's
// cell on the smallest sphere held ~25% of its emission and b_1 was the candidates', ~15% standard error
// at 1024 of them): unbiased against plain camera rays, their spread over seeds what they state, and
// precise to well under 1%. The Cornell box's light is not small (its footprint covers thousands of cells).
TEST(EmissionEstimate, SmallBrightLightsAreFoundByTheirGeometry) {
  const std::unique_ptr<RenderScene> plates = bundledScene("glossy-plates", 64);
  uint64_t smallLights = 0;
  const std::vector<uint8_t> marks = smallLightCells(*plates, 4, &smallLights);
  ASSERT_EQ(marks.size(), size_t(256 * 256));
  uint64_t marked = 0;
  for (uint8_t m : marks) marked += m;
  EXPECT_EQ(smallLights, 3u) << "the spheres of radius 0.03, 0.1 and 0.3";
  EXPECT_GT(marked, 9u);
  EXPECT_LT(marked, 3 * (kFootprintMaxCells + 4 * 16 + 4));  // each footprint and its ring of neighbours
  uint64_t boxLights = 0;
  const std::vector<uint8_t> boxMarks = smallLightCells(cornell(), 7, &boxLights);
  EXPECT_EQ(boxLights, 0u);
  EXPECT_EQ(std::count(boxMarks.begin(), boxMarks.end(), uint8_t(1)), 0);

  // Plain rays over the film: b_1 = E[c_1] (E1), whatever the image of the small spheres.
  const Mean plain = plainEmission(4000000, 91, *plates);
  ASSERT_LT(plain.stdErr / plain.mean, 0.05) << "the check must be able to fail";

  constexpr int kSeeds = 16;
  const auto [mean, spread, statedSe] = overSeeds(
      kSeeds, [&](uint64_t seed) { return emissionEstimate(*plates, squareSettings(seed, 64)); },
      [&](const EmissionEstimate& e, int seed) {
        EXPECT_TRUE(e.estimated) << seed;
        EXPECT_EQ(e.smallLights, 3u) << seed;
        EXPECT_GE(e.edgeCells, marked) << seed << ": every marked cell gets the outline's rays";
        EXPECT_LT(e.maxCellShare, kEmissionMaxCellShare) << seed;
      });
  EXPECT_NEAR(mean, plain.mean, 4 * std::hypot(plain.stdErr, spread / std::sqrt(double(kSeeds))))
      << "plain " << plain.mean << " +- " << plain.stdErr;
  // 16 runs pin the spread to +-18% (1 sigma): 3 sigma either way.
  EXPECT_GT(statedSe, 0.5 * spread) << "spread " << spread << " stated " << statedSe;
  EXPECT_LT(statedSe, 2.2 * spread) << "spread " << spread << " stated " << statedSe;
  EXPECT_LT(spread / mean, 0.01) << "spread " << spread << " of " << mean;

  // mmlt with its length 1 in the chains (--direct-light chains, as these settings ask) takes it: b_1 is the
  // rays' (its candidates, beside a small light, grow as their variance asks: they place the chains).
  const ChainJobSpec* mmlt = findChainJobSpec("mmlt");
  ASSERT_TRUE(mmlt);
  const RenderSettings s = squareSettings(2, 64);
  const MarkovChainBootstrap boot = bootstrapMarkovChainJob(*mmlt, *plates, s);
  const LengthBootstrap& l1 = boot.result.lengths.front();
  ASSERT_EQ(l1.pathLength, 1);
  EmissionEstimate e = emissionEstimate(*plates, s);
  e.estimate.sampleVar = e.estimate.bulkVar = l1.estimate.sampleVar;  // as the bootstrap sets it
  EXPECT_EQ(l1.estimate, e.estimate);
}

// A scene of many lights draws fewer footprint points per light (kFootprintPointBudget in all), and its
// small lights still mark their cells: glossy-plates with 100 copies of its smallest sphere behind the
// camera (lights that never reach the film but share the budget: 50^2 points each instead of 64^2).
TEST(EmissionEstimate, ManyLightsShareThePointBudgetAndSmallOnesStillMark) {
  SceneDesc desc = loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/glossy-plates.xml");
  desc.camera.width = desc.camera.height = 64;
  const std::unique_ptr<RenderScene> four = RenderScene::build(desc);
  size_t smallest = desc.meshes.size();
  float smallestExtent = 0;
  for (size_t m = 0; m < desc.meshes.size(); ++m) {
    if (!desc.meshes[m].emission) continue;
    float lo = desc.meshes[m].positions[0].x, hi = lo;
    for (const Vec3& p : desc.meshes[m].positions) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
    if (smallest == desc.meshes.size() || hi - lo < smallestExtent) smallest = m, smallestExtent = hi - lo;
  }
  ASSERT_LT(smallest, desc.meshes.size());
  for (int c = 0; c < 100; ++c) {
    MeshDesc copy = desc.meshes[smallest];
    for (Vec3& p : copy.positions) p = p + Vec3(float(c % 10), float(c / 10), 40.0f);  // behind the camera (z = 15)
    desc.meshes.push_back(std::move(copy));
  }
  const std::unique_ptr<RenderScene> many = RenderScene::build(desc);
  EXPECT_EQ(footprintPointsPerSide(*four), 64);
  EXPECT_EQ(footprintPointsPerSide(*many), 50);  // floor(sqrt(2^18 / 104))
  uint64_t fourLights = 0, manyLights = 0;
  const std::vector<uint8_t> a = smallLightCells(*four, 4, &fourLights), b = smallLightCells(*many, 4, &manyLights);
  EXPECT_EQ(fourLights, 3u);
  EXPECT_EQ(manyLights, 3u) << "the copies never reach the film";
  uint64_t both = 0, onlyA = 0, onlyB = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    both += a[i] && b[i];
    onlyA += a[i] && !b[i];
    onlyB += b[i] && !a[i];
  }
  EXPECT_GT(both, 0u);
  EXPECT_LE(onlyA + onlyB, both / 10) << "both " << both << ", only with 4096 points " << onlyA << ", only with fewer " << onlyB;
}

// A --time budget bootstraps twice (a probe, then the size that fits): the second takes the first's
// camera rays instead of tracing them again, and is the same bootstrap, bit for bit, as one without it
// (the rays still count against its budget, so --bootstrap with the resolved size reproduces it). Rays of
// another seed, film or depth are not taken.
TEST(EmissionEstimate, ASecondBootstrapReusesTheFirstsRays) {
  const ChainJobSpec* mmlt = findChainJobSpec("mmlt");
  ASSERT_TRUE(mmlt);
  RenderSettings probe = settings("mmlt", 5);
  probe.bootstrapSamples = 1024;
  const MarkovChainBootstrap first = bootstrapMarkovChainJob(*mmlt, cornell(), probe);
  ASSERT_TRUE(first.emission && first.emission->estimated) << "the rays' b_1 is not used: the test checks nothing";
  EXPECT_GT(first.raySeconds, 0);
  const auto same = [](const MarkovChainBootstrap& a, const MarkovChainBootstrap& b) {
    ASSERT_EQ(a.result.lengths.size(), b.result.lengths.size());
    for (size_t l = 0; l < a.result.lengths.size(); ++l) {
      EXPECT_EQ(a.result.lengths[l].c, b.result.lengths[l].c) << "length slot " << l;
      EXPECT_EQ(a.result.lengths[l].estimate.b, b.result.lengths[l].estimate.b) << "length slot " << l;
      EXPECT_EQ(a.result.lengths[l].estimate.stdErr, b.result.lengths[l].estimate.stdErr) << "length slot " << l;
    }
    EXPECT_EQ(a.result.b, b.result.b);
    EXPECT_EQ(a.result.bStdErr, b.result.bStdErr);
  };
  RenderSettings larger = probe;
  larger.bootstrapSamples = 4096;
  const MarkovChainBootstrap reused = bootstrapMarkovChainJob(*mmlt, cornell(), larger, &first);
  const MarkovChainBootstrap fresh = bootstrapMarkovChainJob(*mmlt, cornell(), larger);
  EXPECT_EQ(reused.raySeconds, 0) << "the rays were traced again";
  EXPECT_GT(fresh.raySeconds, 0);
  EXPECT_GT(reused.result.candidates, first.result.candidates) << "the sizes do not differ: the test checks nothing";
  same(reused, fresh);
  for (const auto& change : std::vector<std::function<void(RenderSettings&)>>{
           [](RenderSettings& s) { s.seed = 6; }, [](RenderSettings& s) { s.integrator.maxDepth = 3; }}) {
    RenderSettings other = larger;
    change(other);
    const MarkovChainBootstrap notReused = bootstrapMarkovChainJob(*mmlt, cornell(), other, &first);
    EXPECT_GT(notReused.raySeconds, 0) << "another job's rays were taken";
    same(notReused, bootstrapMarkovChainJob(*mmlt, cornell(), other));
  }
}

// The bundled Cornell box at 32 x 32 (seed 7, 4000 candidates, depth 4: the farm tests' job): its light,
// thin on the film, escaped all 1000 candidates of length 1 of the first round, so no chain rendered it.
// The rays see it, and the bootstrap draws more candidates until one carries light.
TEST(EmissionEstimate, ALightTheCandidatesMissedStillGetsChains) {
  const std::unique_ptr<RenderScene> scene = bundledScene("cornell-box", 32);
  const ChainJobSpec* mmlt = findChainJobSpec("mmlt");
  ASSERT_TRUE(mmlt);
  RenderSettings s = squareSettings(7, 32);
  s.bootstrapSamples = 4000;
  s.mutationsPerPixel = 8;
  const MarkovChainBootstrap boot = bootstrapMarkovChainJob(*mmlt, *scene, s);
  const LengthBootstrap& l1 = boot.result.lengths.front();
  ASSERT_EQ(l1.pathLength, 1);
  EXPECT_GT(l1.c.size(), 1000u) << "the first round's candidates did not miss the light: the test checks nothing";
  double candidatesB = 0;
  for (double c : l1.c) candidatesB += c;
  EXPECT_GT(candidatesB, 0) << "no candidate of length 1 carries light";
  EXPECT_GT(l1.estimate.b, 0);
  const JobPlan plan = planMarkovChainJob(*mmlt, *scene, s, boot);
  int chainsOfLengthOne = 0;
  for (const WorkUnit& u : plan.units) chainsOfLengthOne += u.pathLength == 1 && u.mutations > 0;
  EXPECT_GT(chainsOfLengthOne, 0);
}

}  // namespace
}  // namespace mlt
