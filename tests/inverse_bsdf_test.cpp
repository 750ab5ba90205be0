// Inverses of every BSDF's sample() (reversible-jump MLT, Bitterli et al. 2017, sec. 5-6):
//  - round trip: wi = sample(wo, u); u' = invertSample(wo, wi, gamma); sample(wo, u') == wi to 1e-4, the
//    same lobe (delta flag), and the inverse's Jacobian equals the pdfW sample() reports;
//  - probabilistic inverses (lobe choice by T(t) of eq. 44, ambiguous intervals and unread coordinates
//    by eq. 40): the inverted (uComponent, uDir) of uniform u is uniform again on the routine's success
//    region (two-sample chi-square against the u's themselves), and the test fails when the ambiguous
//    interval is inverted to a fixed point (Figure 3c's mistake);
//  - Russian roulette's inverse.
// Fixed seeds throughout.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "common/bsdf/bsdfs.h"
#include "common/core/rng.h"
#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"
#include "tests/support/two_sample_chi2.h"

namespace mlt {
namespace {

struct NamedBsdf {
  std::string name;
  std::shared_ptr<Bsdf> bsdf;
};

TexturePtr constant(float v) { return std::make_shared<ConstantTexture>(Color(v)); }

std::vector<NamedBsdf> everyBsdf() {
  const Color goldEta(0.143f, 0.374f, 1.442f), goldK(3.983f, 2.385f, 1.603f);
  std::vector<NamedBsdf> v;
  v.push_back({"diffuse", makeDiffuse(constant(0.7f))});
  v.push_back({"dielectric_1.5", makeDielectric(1.5f, constant(1.0f), constant(1.0f))});
  v.push_back({"dielectric_0.75", makeDielectric(0.75f, constant(1.0f), constant(1.0f))});
  v.push_back({"thin_dielectric", makeThinDielectric(1.5f, constant(1.0f), constant(1.0f))});
  v.push_back({"conductor_gold", makeConductor(goldEta, goldK, false, constant(1.0f))});
  v.push_back({"conductor_mirror", makeConductor(Color(0.0f), Color(1.0f), true, constant(1.0f))});
  v.push_back({"rough_conductor_ggx_0.3", makeRoughConductor(MicrofacetType::GGX, 0.3f, nullptr, goldEta, goldK, false, constant(1.0f))});
  v.push_back({"rough_conductor_ggx_0.05", makeRoughConductor(MicrofacetType::GGX, 0.05f, nullptr, goldEta, goldK, false, constant(1.0f))});
  v.push_back({"rough_conductor_beckmann_0.2",
               makeRoughConductor(MicrofacetType::Beckmann, 0.2f, nullptr, goldEta, goldK, false, constant(1.0f))});
  v.push_back({"rough_dielectric_ggx_0.3", makeRoughDielectric(MicrofacetType::GGX, 0.3f, nullptr, 1.5f, constant(1.0f), constant(1.0f))});
  v.push_back({"rough_dielectric_beckmann_0.2",
               makeRoughDielectric(MicrofacetType::Beckmann, 0.2f, nullptr, 1.33f, constant(1.0f), constant(1.0f))});
  v.push_back({"plastic", makePlastic(1.5f, constant(0.5f), constant(1.0f), false)});
  v.push_back({"rough_plastic_ggx_0.2", makeRoughPlastic(MicrofacetType::GGX, 0.2f, 1.5f, constant(0.5f), constant(1.0f), false)});
  v.push_back({"rough_plastic_beckmann_0.3",
               makeRoughPlastic(MicrofacetType::Beckmann, 0.3f, 1.5f, constant(0.3f), constant(1.0f), true)});
  v.push_back({"twosided_diffuse", makeTwoSided(makeDiffuse(constant(0.7f)))});
  v.push_back({"twosided_rough_plastic",
               makeTwoSided(makeRoughPlastic(MicrofacetType::GGX, 0.2f, 1.5f, constant(0.5f), constant(1.0f), false))});
  v.push_back({"twosided_rough_conductor",
               makeTwoSided(makeRoughConductor(MicrofacetType::GGX, 0.3f, nullptr, goldEta, goldK, false, constant(1.0f)))});
  return v;
}

InverseGamma randomGamma(Pcg32& rng) {
  InverseGamma g;
  g.pick = rng.uniform();
  g.fill = rng.uniform2();
  return g;
}

bool inUnit(float u) { return u >= 0 && u < 1; }

// Round trip and Jacobian over many random (wo, u): every forward sample must be inverted (a handful of
// numerically hopeless grazing cases may reject, never more than 0.2%), and every inverse must land on
// the same direction and lobe with the forward pdf as Jacobian.
TEST(InverseBsdf, RoundTripReproducesDirectionAndJacobianIsPdf) {
  constexpr int kSamples = 20000;
  for (const NamedBsdf& nb : everyBsdf()) {
    SCOPED_TRACE(nb.name);
    Pcg32 rng(11, 3);
    const BsdfQuery q{Vec2(0.3f, 0.6f), TransportMode::Radiance};
    int forward = 0, rejected = 0, mismatched = 0;
    std::string firstMismatch;
    for (int i = 0; i < kSamples; ++i) {
      const Vec3 wo = sampleUniformSphere(rng.uniform2());
      const float uc = rng.uniform();
      const Vec2 ud = rng.uniform2();
      const std::optional<BsdfSample> s = nb.bsdf->sample(wo, uc, ud, q);
      const InverseGamma gamma = randomGamma(rng);
      if (!s || !(s->pdfW > 0)) continue;
      ++forward;
      const std::optional<BsdfSampleInverse> inv = nb.bsdf->invertSample(wo, s->wi, gamma, q);
      if (!inv) {
        ++rejected;
        continue;
      }
      const std::optional<BsdfSample> s2 =
          inUnit(inv->uComponent) && inUnit(inv->uDir.x) && inUnit(inv->uDir.y)
              ? nb.bsdf->sample(wo, inv->uComponent, inv->uDir, q)
              : std::nullopt;
      const bool ok = s2 && length(s2->wi - s->wi) <= 1e-4f && s2->delta == s->delta &&
                      std::fabs(inv->jacobian - s->pdfW) <= 1e-4f * s->pdfW;
      if (!ok) {
        if (mismatched++ == 0)
          firstMismatch = "wo=(" + std::to_string(wo.x) + "," + std::to_string(wo.y) + "," + std::to_string(wo.z) +
                          ") u=(" + std::to_string(uc) + "," + std::to_string(ud.x) + "," + std::to_string(ud.y) +
                          ") -> u'=(" + std::to_string(inv->uComponent) + "," + std::to_string(inv->uDir.x) + "," +
                          std::to_string(inv->uDir.y) + ") J=" + std::to_string(inv->jacobian) +
                          " pdf=" + std::to_string(s->pdfW) +
                          (s2 ? " |dwi|=" + std::to_string(length(s2->wi - s->wi)) : std::string(" s2 absorbed"));
      }
    }
    EXPECT_GT(forward, kSamples / 4);
    EXPECT_EQ(mismatched, 0) << firstMismatch;
    EXPECT_LE(rejected, forward / 500) << rejected << " of " << forward << " rejected";
  }
}

// An inverse must reject what sample() cannot produce: directions on the wrong side, or off a Dirac lobe.
TEST(InverseBsdf, RejectsDirectionsTheRoutineCannotProduce) {
  const BsdfQuery q{Vec2(0.5f, 0.5f), TransportMode::Radiance};
  const Vec3 wo = normalize(Vec3(0.3f, -0.2f, 0.8f));
  const Vec3 offLobe = normalize(Vec3(0.1f, 0.5f, 0.7f));
  for (const NamedBsdf& nb : everyBsdf()) {
    SCOPED_TRACE(nb.name);
    if (nb.bsdf->isDelta()) {
      EXPECT_FALSE(nb.bsdf->invertSample(wo, offLobe, InverseGamma{}, q));
    }
  }
  const auto diffuse = makeDiffuse(constant(0.5f));
  EXPECT_FALSE(diffuse->invertSample(wo, Vec3(0, 0.6f, -0.8f), InverseGamma{}, q));  // below the surface
  EXPECT_FALSE(diffuse->invertSample(-wo, offLobe, InverseGamma{}, q));              // wo on the back
}

// Collects A (forward u's that succeed) and B (inverted numbers of independent forward samples).
void collect(const Bsdf& bsdf, const Vec3& wo, int n, bool fixedGamma, std::vector<float>* a, std::vector<float>* b) {
  const BsdfQuery q{Vec2(0.5f, 0.5f), TransportMode::Radiance};
  Pcg32 ra(7, 1), rb(7, 2);
  for (int i = 0; i < n; ++i) {
    const float uc = ra.uniform();
    const Vec2 ud = ra.uniform2();
    if (bsdf.sample(wo, uc, ud, q)) a->insert(a->end(), {uc, ud.x, ud.y});
  }
  for (int i = 0; i < n; ++i) {
    const float uc = rb.uniform();
    const Vec2 ud = rb.uniform2();
    const std::optional<BsdfSample> s = bsdf.sample(wo, uc, ud, q);
    const InverseGamma gamma = fixedGamma ? InverseGamma{} : randomGamma(rb);
    if (!s) continue;
    const std::optional<BsdfSampleInverse> inv = bsdf.invertSample(wo, s->wi, gamma, q);
    if (inv) b->insert(b->end(), {inv->uComponent, inv->uDir.x, inv->uDir.y});
  }
}

TEST(InverseBsdf, ProbabilisticInverseOfUniformIsUniform) {
  constexpr int kTests = 9;
  const Vec3 woA = normalize(Vec3(0.4f, 0.1f, 0.9f)), woB = normalize(Vec3(-0.8f, 0.3f, 0.35f));
  for (const NamedBsdf& nb : everyBsdf()) {
    if (nb.name != "rough_plastic_ggx_0.2" && nb.name != "rough_plastic_beckmann_0.3" && nb.name != "plastic" &&
        nb.name != "dielectric_1.5" && nb.name != "rough_dielectric_ggx_0.3" && nb.name != "thin_dielectric" &&
        nb.name != "diffuse" && nb.name != "conductor_gold" && nb.name != "twosided_rough_plastic")
      continue;
    for (const Vec3& wo : {woA, woB}) {
      SCOPED_TRACE(nb.name + (wo.z > 0.5f ? " near normal" : " grazing"));
      std::vector<float> a, b;
      collect(*nb.bsdf, wo, 150000, false, &a, &b);
      const test::TwoSampleResult r = test::twoSampleChi2(a, b, 3, 8, 0.01, 2 * kTests);
      EXPECT_TRUE(r.passed) << r.message;
    }
  }
}

// Figure 3(c)'s mistake: the ambiguous interval of a lobe choice (and the unread coordinates) inverted to
// a fixed point instead of a uniform one. The same test must then fail.
TEST(InverseBsdf, FixedPointInverseOfAmbiguousIntervalIsDetected) {
  for (const NamedBsdf& nb : everyBsdf()) {
    if (nb.name != "rough_plastic_ggx_0.2" && nb.name != "dielectric_1.5") continue;
    SCOPED_TRACE(nb.name);
    std::vector<float> a, b;
    collect(*nb.bsdf, normalize(Vec3(0.4f, 0.1f, 0.9f)), 150000, true, &a, &b);
    const test::TwoSampleResult r = test::twoSampleChi2(a, b, 3, 8);
    EXPECT_FALSE(r.passed) << r.message;
    EXPECT_LT(r.pValue, 1e-6) << r.message;
  }
}

// Roulette keeps the subpath when u < q: the inverse lands in the decision's interval with Jacobian q or
// 1 - q, is uniform there, and rejects impossible decisions.
TEST(InverseRoulette, IntervalAndJacobian) {
  Pcg32 rng(5, 5);
  std::vector<int> hist(10, 0);
  const float q = 0.37f;
  constexpr int n = 100000;
  for (int i = 0; i < n; ++i) {
    const bool survived = rng.uniform() < q;
    const std::optional<RouletteInverse> inv = invertRoulette(q, survived, rng.uniform());
    ASSERT_TRUE(inv);
    ASSERT_EQ(inv->u < q, survived);
    ASSERT_FLOAT_EQ(inv->jacobian, survived ? q : 1 - q);
    hist[std::min(9, int(inv->u * 10))]++;
  }
  for (int c : hist) EXPECT_NEAR(c, n / 10, 5 * std::sqrt(n / 10.0));  // 5 sigma per bin
  EXPECT_FALSE(invertRoulette(0.0f, true, 0.5f));
  EXPECT_FALSE(invertRoulette(1.0f, false, 0.5f));
  EXPECT_LT(invertRoulette(1e-7f, true, 0.9999f)->u, 1e-7f);
}

}  // namespace
}  // namespace mlt
