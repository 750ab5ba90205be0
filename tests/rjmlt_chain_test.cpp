// The reversible-jump chain state (common/methods/rjmlt/rjmlt_chain.h) in the shared chain loop (chain.h):
//  - KelemenSource::write is undone exactly by reject();
//  - the chain's stationary distribution is MMLT's target: the share of the target in each technique
//    (s, t) and in each film tile, estimated from the chain's expected-value splats (weight * c summed per
//    bin), matches an independent-sample estimate of E[c 1_bin] / E[c] (z-test over independent chains);
//    with the Jacobian of eq. 38 dropped the same test fails;
//  - technique changes are accepted far more often than MMLT's technique-changing small steps.
// Scenes: the small Cornell box (area light), the point + spot variant (delta lights: s = 0 is
// impossible for them), the specular variant (Dirac lobes). Fixed seeds.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "common/methods/rjmlt/rjmlt_chain.h"
#include "common/methods/mmlt/mmlt_method.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

constexpr int kFilm = 16, kTiles = 2;

TEST(KelemenWrite, RejectRestoresWrittenCoordinates) {
  KelemenSource src(KelemenParams{}, 1, 2, 3);
  std::vector<float> before;
  for (int i = 0; i < 8; ++i) before.push_back(src.read(int(Stream::Camera), i));
  src.accept();
  src.startIteration(MutationType::Small);
  for (int i = 0; i < 12; ++i) src.write(int(Stream::Camera), i, 0.125f * float(i % 8));
  EXPECT_EQ(src.read(int(Stream::Camera), 3), 0.375f);  // a written coordinate is not mutated when read
  src.reject();
  for (int i = 0; i < 8; ++i) EXPECT_EQ(src.storedValues(int(Stream::Camera))[i], before[i]);
  src.startIteration(MutationType::Small);
  src.write(int(Stream::Light), 2, 0.5f);
  src.accept();
  EXPECT_EQ(src.storedValues(int(Stream::Light))[2], 0.5f);
}

// Accumulates weight * c per technique and per tile: each chain step distributes total weight 1 in
// units of 1 / c (chain.h), so these sums are the chain's time-averaged occupancy of the bins.
struct OccupancySink final : ChainSink {
  std::vector<double> technique, tile;
  explicit OccupancySink(int n) : technique(n, 0.0), tile(kTiles * kTiles, 0.0) {}
  void splat(const PathContribution& path, double weight) override {
    for (const Splat& sp : path.splats) {
      const double c = weight * luminance(sp.L);
      technique[sp.s] += c;
      const int tx = std::min(kTiles - 1, int(sp.pRaster.x * kTiles / kFilm));
      const int ty = std::min(kTiles - 1, int(sp.pRaster.y * kTiles / kFilm));
      tile[ty * kTiles + tx] += c;
    }
  }
};

double targetValue(const PathContribution& pc) {
  double c = 0;
  for (const Splat& sp : pc.splats) c += luminance(sp.L);
  return c;
}

struct Shares {
  std::vector<double> mean, se;  // techniques then tiles
};

// Independent estimate of E[c 1_bin] / E[c] with a delta-method standard error.
Shares independentShares(const RenderScene& scene, int k, int samples) {
  const int n = mmltTechniqueCount(k), bins = n + kTiles * kTiles;
  std::vector<double> sum(bins, 0.0), sum2(bins, 0.0);
  double total = 0, total2 = 0;
  std::vector<double> cross(bins, 0.0);
  BdptWorkspace ws;
  ws.reserve(k + 2, k + 1);
  for (int i = 0; i < samples; ++i) {
    IndependentSource src(99, uint64_t(i));
    const int s = mmltTechniqueOf(src, k);
    MmltPath p;
    double c = 0;
    int tile = 0;
    if (traceTechnique(scene, src, s, k + 1 - s, MisHeuristic::Power, ws, &p)) {
      c = luminance(p.C) * p.weight * n;
      tile = std::min(kTiles - 1, int(p.pRaster.y * kTiles / kFilm)) * kTiles +
             std::min(kTiles - 1, int(p.pRaster.x * kTiles / kFilm));
    }
    total += c;
    total2 += c * c;
    for (int b : {s, n + tile}) {
      sum[b] += c;
      sum2[b] += c * c;
      cross[b] += c * c;
    }
  }
  Shares r;
  const double N = samples, mT = total / N;
  for (int b = 0; b < bins; ++b) {
    const double mB = sum[b] / N, ratio = mB / mT;
    // Var(ratio) ~ (Var(cB) - 2 ratio Cov(cB, c) + ratio^2 Var(c)) / (N mT^2)
    const double vB = sum2[b] / N - mB * mB, vT = total2 / N - mT * mT, cov = cross[b] / N - mB * mT;
    r.mean.push_back(ratio);
    r.se.push_back(std::sqrt(std::max(0.0, vB - 2 * ratio * cov + ratio * ratio * vT) / (N * mT * mT)));
  }
  return r;
}

struct ChainResult {
  Shares shares;
  std::vector<uint64_t> proposed, accepted;  // per kind
};

ChainResult chainShares(const RenderScene& scene, int k, const RjmltSettings& settings, int chains, int steps) {
  const int n = mmltTechniqueCount(k), bins = n + kTiles * kTiles;
  std::vector<std::vector<double>> perChain;
  ChainResult out;
  out.proposed.assign(3, 0);
  out.accepted.assign(3, 0);
  BdptWorkspace ws;
  ws.reserve(k + 2, k + 1);
  for (int ch = 0; ch < chains; ++ch) {
    // Start from a candidate with c > 0 (the first one found), then burn in.
    uint64_t cand = 0;
    for (;; ++cand) {
      if (cand >= 100000) {
        ADD_FAILURE() << "no contribution at this length";
        return out;
      }
      IndependentSource probe = IndependentSource::candidate(7, cand);
      const int s = mmltTechniqueOf(probe, k);
      MmltPath p;
      if (traceTechnique(scene, probe, s, k + 1 - s, MisHeuristic::Power, ws, &p) && p.weight > 0) break;
    }
    KelemenSource source(KelemenParams{}, 7, uint64_t(ch), cand);
    RjmltState state(scene, source, k, MisHeuristic::Power, settings, chainRng(7, uint64_t(ch), 2));
    PathContribution current, scratch;
    const double c0 = state.start(current);
    Pcg32 acceptRng = chainRng(7, uint64_t(ch), 1);
    OccupancySink burn(n), sink(n);
    ChainCounts counts = runChain(state, state, ChainConfig{}, burn, acceptRng, steps / 10, current, c0, scratch);
    counts = runChain(state, state, ChainConfig{}, sink, acceptRng, steps, current, targetValue(current), scratch);
    for (int kind = 0; kind < 3; ++kind) {
      out.proposed[kind] += counts.proposed[kind];
      out.accepted[kind] += counts.accepted[kind];
    }
    std::vector<double> row;
    double total = 0;
    for (double v : sink.technique) total += v;
    for (double v : sink.technique) row.push_back(v / total);
    for (double v : sink.tile) row.push_back(v / total);
    perChain.push_back(row);
  }
  for (int b = 0; b < bins; ++b) {
    double m = 0, v = 0;
    for (const auto& row : perChain) m += row[b] / chains;
    for (const auto& row : perChain) v += (row[b] - m) * (row[b] - m) / (chains - 1);
    out.shares.mean.push_back(m);
    out.shares.se.push_back(std::sqrt(v / chains));
  }
  return out;
}

// Sum over bins of z^2 (z = difference / combined standard error) and the largest |z|.
std::pair<double, double> compare(const Shares& a, const Shares& b) {
  double chi2 = 0, worst = 0;
  for (size_t i = 0; i < a.mean.size(); ++i) {
    const double se = std::sqrt(a.se[i] * a.se[i] + b.se[i] * b.se[i]);
    if (!(se > 0)) continue;
    const double z = (a.mean[i] - b.mean[i]) / se;
    chi2 += z * z;
    worst = std::max(worst, std::fabs(z));
  }
  return {chi2, worst};
}

struct SceneCase {
  std::string name;
  SceneDesc desc;
};

TEST(RjmltChain, StationaryDistributionIsTheMmltTarget) {
  const std::vector<SceneCase> cases = {{"cornell", test::smallCornellBox(kFilm, kFilm)},
                                        {"point_spot", test::cornellBoxPointSpot(kFilm, kFilm)},
                                        {"specular", test::cornellBoxSpecular(kFilm, kFilm)}};
  RjmltSettings settings;
  settings.largeStepProb = 0.05;  // mostly jumps and small steps, so that a wrong jump would show
  settings.techniqueProb = 0.4;
  for (const SceneCase& c : cases) {
    const auto scene = RenderScene::build(c.desc);
    for (int k : {2, 3}) {
      SCOPED_TRACE(c.name + " k=" + std::to_string(k));
      settings.proposal = TechniqueProposal::MisWeight;
      const Shares ref = independentShares(*scene, k, 300000);
      const ChainResult chain = chainShares(*scene, k, settings, 16, 20000);
      const auto [chi2, worst] = compare(ref, chain.shares);
      std::printf("[ %-10s k=%d ] chi2 %.1f over %zu bins, max |z| %.2f; jumps accepted %.3f (the MIS-weight proposal may keep the technique)\n",
                  c.name.c_str(), k, chi2, ref.mean.size(), worst,
                  double(chain.accepted[kRjmltTechnique]) / double(std::max<uint64_t>(1, chain.proposed[kRjmltTechnique])));
      EXPECT_LT(worst, 4.5);
      if (c.name == "cornell") {  // the uniform proposal of the other technique too
        settings.proposal = TechniqueProposal::Uniform;
        const ChainResult uni = chainShares(*scene, k, settings, 16, 20000);
        const auto [chi2u, worstU] = compare(ref, uni.shares);
        std::printf("[ %-10s k=%d ] uniform proposal: chi2 %.1f, max |z| %.2f; accepted %.3f\n", c.name.c_str(), k,
                    chi2u, worstU,
                    double(uni.accepted[kRjmltTechnique]) / double(std::max<uint64_t>(1, uni.proposed[kRjmltTechnique])));
        EXPECT_LT(worstU, 4.5);
      }
    }
  }
}

TEST(RjmltChain, DroppingTheJacobianIsDetected) {
  const auto scene = RenderScene::build(test::smallCornellBox(kFilm, kFilm));
  RjmltSettings settings;
  settings.largeStepProb = 0.05;
  settings.techniqueProb = 0.4;
  settings.dropJacobian = true;
  settings.proposal = TechniqueProposal::Uniform;  // a = c_j / c_i: the pdf ratio is missing entirely
  const int k = 3;
  const Shares ref = independentShares(*scene, k, 300000);
  const ChainResult chain = chainShares(*scene, k, settings, 16, 20000);
  const auto [chi2, worst] = compare(ref, chain.shares);
  std::printf("[ no Jacobian k=%d ] chi2 %.1f, max |z| %.2f\n", k, chi2, worst);
  EXPECT_GT(worst, 10.0);
}

}  // namespace
}  // namespace mlt
