// Reversible-jump MLT is unbiased against bdpt, path length by path length (the method's pieces without
// the job pipeline: an independent-sample bootstrap of b_k, chains of RjmltState started in proportion to
// c, expected-value splats scaled by b_k / M, as develop.h does):
//   bdpt_k(tile) = E[ sum over the techniques (s, t) of w C  in the tile ]   (independent samples)
//   rjmlt_k(tile) = b_k / M * sum over the chains' weighted splats in the tile
// Each tile's difference is compared with its standard error (bdpt: sample variance; rjmlt: variance
// across independent chains, plus b_k's standard error). Scenes: two lights of very different size and
// power (a dim panel and a small bright light in a mirror reflector), a thin-lens camera, and every
// bundled scene at a small resolution. Also prints, per path length, the acceptance of rjmlt's technique
// changes next to mmlt's small steps that change the technique (the paper's Figure 4 comparison).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "common/methods/rjmlt/rjmlt_chain.h"
#include "common/methods/mmlt/mmlt_method.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

constexpr int kRes = 16, kTiles = 4;
constexpr uint64_t kSeed = 2026;

int tileOf(Vec2 p) {
  const int tx = std::clamp(int(p.x * kTiles / kRes), 0, kTiles - 1), ty = std::clamp(int(p.y * kTiles / kRes), 0, kTiles - 1);
  return ty * kTiles + tx;
}

struct Estimate {
  std::vector<double> mean, se;  // per tile, luminance
};

// bdpt restricted to length k: every technique of one independent sample, MIS-weighted.
Estimate bdptLength(const RenderScene& scene, int k, int samples) {
  const int n = mmltTechniqueCount(k), T = kTiles * kTiles;
  std::vector<double> sum(T, 0.0), sum2(T, 0.0), x(T);
  BdptWorkspace ws;
  ws.reserve(k + 2, k + 1);
  for (int i = 0; i < samples; ++i) {
    std::fill(x.begin(), x.end(), 0.0);
    IndependentSource src(kSeed + 1, uint64_t(i));
    for (int s = 0; s < n; ++s) {
      const TechniqueSample ts = evaluateTechnique(scene, src, s, k + 1 - s, MisHeuristic::Power, ws);
      if (ts.weight > 0 && !ts.C.isBlack()) x[tileOf(ts.pRaster)] += luminance(ts.C) * ts.weight;
    }
    for (int t = 0; t < T; ++t) {
      sum[t] += x[t];
      sum2[t] += x[t] * x[t];
    }
  }
  Estimate e;
  for (int t = 0; t < T; ++t) {
    const double m = sum[t] / samples;
    e.mean.push_back(m);
    e.se.push_back(std::sqrt(std::max(0.0, sum2[t] / samples - m * m) / samples));
  }
  return e;
}

struct SplatSink final : ChainSink {
  std::vector<double> tile = std::vector<double>(kTiles * kTiles, 0.0);
  void splat(const PathContribution& path, double weight) override {
    for (const Splat& sp : path.splats) tile[tileOf(sp.pRaster)] += weight * luminance(sp.L);
  }
};

double targetValue(const PathContribution& pc) {
  double c = 0;
  for (const Splat& sp : pc.splats) c += luminance(sp.L);
  return c;
}

struct RjResult {
  Estimate estimate;
  uint64_t jumpsProposed = 0, jumpsAccepted = 0, inversionFailures = 0, retraceFailures = 0;
};

RjResult rjmltLength(const RenderScene& scene, int k, int bootstrap, int chains, int mutations) {
  // Bootstrap: c of candidates (the chains' start states replay them), b_k = mean c.
  std::vector<double> c(bootstrap), cdf(bootstrap + 1, 0.0);
  BdptWorkspace ws;
  ws.reserve(k + 2, k + 1);
  double sum = 0, sum2 = 0;
  for (int i = 0; i < bootstrap; ++i) {
    IndependentSource src = IndependentSource::candidate(kSeed, uint64_t(i));
    const int s = mmltTechniqueOf(src, k);
    MmltPath p;
    c[i] = traceTechnique(scene, src, s, k + 1 - s, MisHeuristic::Power, ws, &p)
               ? luminance(p.C) * p.weight * mmltTechniqueCount(k)
               : 0.0;
    sum += c[i];
    sum2 += c[i] * c[i];
    cdf[i + 1] = sum;
  }
  RjResult r;
  const int T = kTiles * kTiles;
  if (!(sum > 0)) {
    r.estimate.mean.assign(T, 0.0);
    r.estimate.se.assign(T, 0.0);
    return r;
  }
  const double b = sum / bootstrap;
  const double bRelSe = std::sqrt(std::max(0.0, sum2 / bootstrap - b * b) / bootstrap) / b;
  Pcg32 pick(kSeed, 99);
  std::vector<std::vector<double>> perChain;
  for (int ch = 0; ch < chains; ++ch) {
    const double u = pick.uniformDouble() * sum;
    const int cand = int(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1;
    KelemenSource source(KelemenParams{}, kSeed, uint64_t(ch), uint64_t(std::clamp(cand, 0, bootstrap - 1)));
    RjmltState state(scene, source, k, MisHeuristic::Power, RjmltSettings{}, chainRng(kSeed, uint64_t(ch), 2));
    PathContribution current, scratch;
    const double c0 = state.start(current);
    EXPECT_NEAR(c0, c[std::clamp(cand, 0, bootstrap - 1)], 1e-6 * c0) << "the start state replays its candidate";
    Pcg32 acceptRng = chainRng(kSeed, uint64_t(ch), 1);
    SplatSink sink;
    const ChainCounts counts = runChain(state, state, ChainConfig{}, sink, acceptRng, uint64_t(mutations), current,
                                        targetValue(current), scratch);
    (void)counts;
    r.jumpsProposed += state.changesProposed();
    r.jumpsAccepted += state.changesAccepted();
    r.inversionFailures += state.inversionFailures();
    r.retraceFailures += state.retraceFailures();
    std::vector<double> est(T);
    for (int t = 0; t < T; ++t) est[t] = b * sink.tile[t] / mutations;
    perChain.push_back(est);
  }
  for (int t = 0; t < T; ++t) {
    double m = 0, v = 0;
    for (const auto& e : perChain) m += e[t] / chains;
    for (const auto& e : perChain) v += (e[t] - m) * (e[t] - m) / (chains - 1);
    r.estimate.mean.push_back(m);
    r.estimate.se.push_back(std::sqrt(v / chains + m * m * bRelSe * bRelSe));
  }
  return r;
}

// mmlt's small steps that change the technique (Connect[0] crosses an interval): proposed and accepted.
std::pair<uint64_t, uint64_t> mmltTechniqueSmallSteps(const RenderScene& scene, int k, int steps) {
  IntegratorSettings integrator;
  integrator.maxDepth = k;
  MmltTarget target(scene, integrator);
  uint64_t cand = 0;
  PathContribution x, y;
  for (;; ++cand) {
    if (cand == 200000) return {0, 0};  // no contribution at this length
    IndependentSource probe = IndependentSource::candidate(kSeed, cand);
    target.evaluate(probe, k, x);
    if (targetValue(x) > 0) break;
  }
  KelemenSource source(KelemenParams{}, kSeed, 7, cand);
  target.evaluate(source, k, x);
  source.accept();
  double cx = targetValue(x);
  int sx = mmltTechniqueOf(source, k);
  Pcg32 rng(kSeed, 5);
  uint64_t proposed = 0, accepted = 0;
  for (int i = 0; i < steps; ++i) {
    source.startIteration(MutationType::Small);
    target.evaluate(source, k, y);
    const int sy = mmltTechniqueOf(source, k);
    const double cy = targetValue(y);
    const bool accept = rng.uniformDouble() < std::min(1.0, cy / cx);
    if (sy != sx) {
      ++proposed;
      accepted += accept;
    }
    if (accept) {
      source.accept();
      std::swap(x, y);
      cx = cy;
      sx = sy;
    } else {
      source.reject();
    }
  }
  return {proposed, accepted};
}

void checkScene(const std::string& name, const SceneDesc& desc, const std::vector<int>& lengths) {
  const auto scene = RenderScene::build(desc);
  for (int k : lengths) {
    SCOPED_TRACE(name + " k=" + std::to_string(k));
    const Estimate ref = bdptLength(*scene, k, 60000);
    const RjResult rj = rjmltLength(*scene, k, 40000, 32, 6000);
    double worst = 0, totRef = 0, totRj = 0, varRef = 0, varRj = 0;
    for (int t = 0; t < kTiles * kTiles; ++t) {
      const double se = std::hypot(ref.se[t], rj.estimate.se[t]);
      if (se > 0) worst = std::max(worst, std::fabs(ref.mean[t] - rj.estimate.mean[t]) / se);
      totRef += ref.mean[t];
      totRj += rj.estimate.mean[t];
      varRef += ref.se[t] * ref.se[t];
      varRj += rj.estimate.se[t] * rj.estimate.se[t];
    }
    const double zTotal = (totRj - totRef) / std::sqrt(varRef + varRj + 1e-30);
    const auto [mp, ma] = mmltTechniqueSmallSteps(*scene, k, 20000);
    std::printf("[ %-16s k=%d ] bdpt %.5g  rjmlt %.5g  (z %.2f, worst tile |z| %.2f); technique changes accepted: "
                "rjmlt %.3f (%llu jumps; refused: %llu inversions, %llu re-traces), mmlt small steps %.3f (%llu)\n",
                name.c_str(), k, totRef, totRj, zTotal, worst,
                double(rj.jumpsAccepted) / double(std::max<uint64_t>(1, rj.jumpsProposed)),
                (unsigned long long)rj.jumpsProposed, (unsigned long long)rj.inversionFailures,
                (unsigned long long)rj.retraceFailures, double(ma) / double(std::max<uint64_t>(1, mp)),
                (unsigned long long)mp);
    EXPECT_LT(std::fabs(zTotal), 4.0);
    EXPECT_LT(worst, 4.5);  // 16 tiles: P(max |z| > 4.5) < 1e-4 for correct estimators
  }
}

TEST(RjmltUnbiased, TwoLightsOfVeryDifferentSizeAndPower) {
  checkScene("two-lights", test::twoLightsReflector(kRes, kRes), {2, 3, 4});
}

TEST(RjmltUnbiased, ThinLensCamera) {
  SceneDesc d = test::smallCornellBox(kRes, kRes);
  d.camera.type = CameraDesc::Type::ThinLens;
  d.camera.apertureRadius = 0.3f;
  d.camera.focusDistance = 3.0f;
  checkScene("thin-lens", d, {2, 3});
}

class RjmltBundled : public ::testing::TestWithParam<const char*> {};

TEST_P(RjmltBundled, MatchesBdpt) {
  const std::string file = std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + GetParam() + ".xml";
  SceneDesc desc = loadMitsubaScene(file, {{"res", std::to_string(kRes)}});
  desc.camera.width = desc.camera.height = kRes;
  checkScene(GetParam(), desc, {2, 3});
}

INSTANTIATE_TEST_SUITE_P(Bundled, RjmltBundled,
                         ::testing::Values("cornell-box", "cornell-spheres", "door-ajar", "glossy-plates",
                                           "caustic-mirror", "furnace-sphere"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string n = info.param;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

}  // namespace
}  // namespace mlt
