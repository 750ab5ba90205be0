// BSDF and texture tests, and the chi-square framework's own tests (tests/support/chi2.h).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <unistd.h>
#include <string>
#include <vector>

#include "common/bsdf/fresnel.h"
#include "common/bsdf/make_bsdf.h"
#include "common/bsdf/microfacet.h"
#include "common/bsdf/texture.h"
#include "common/core/rng.h"
#include "common/core/sampling.h"
#include "common/scene/scene_desc.h"
#include "tests/support/chi2.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
#pragma GCC diagnostic pop

namespace mlt {
namespace {

using test::Chi2Result;
using test::chi2Test2D;
using test::chi2TestSphere;

// ---------------------------------------------------------------------------------------------------
// The chi-square framework
// ---------------------------------------------------------------------------------------------------
TEST(Chi2Framework, IncompleteGammaMatchesKnownValues) {
  // Q(1, x) = exp(-x); chi-square with 2 dof: P(X >= s) = exp(-s/2).
  EXPECT_NEAR(test::regularizedGammaQ(1.0, 0.7), std::exp(-0.7), 1e-12);
  EXPECT_NEAR(test::chi2SurvivalProbability(5.0, 2), std::exp(-2.5), 1e-12);
  // Q(0.5, x) = erfc(sqrt(x)).
  EXPECT_NEAR(test::regularizedGammaQ(0.5, 3.2), std::erfc(std::sqrt(3.2)), 1e-12);
  EXPECT_NEAR(test::regularizedGammaQ(0.5, 0.2), std::erfc(std::sqrt(0.2)), 1e-12);
  // Tabulated: chi-square 95th percentile for 10 dof is 18.307; for 100 dof 124.342.
  EXPECT_NEAR(test::chi2SurvivalProbability(18.307, 10), 0.05, 1e-4);
  EXPECT_NEAR(test::chi2SurvivalProbability(124.342, 100), 0.05, 1e-4);
}

TEST(Chi2Framework, AdaptiveSimpsonIntegratesPeakedFunction) {
  // A narrow Gaussian bump (sigma = 1/20 of the side) inside a bin-sized square: integral = 2 pi sigma^2.
  const double s = 0.005;
  auto f = [&](double x, double y) {
    const double dx = x - 0.03141, dy = y - 0.07;
    return std::exp(-(dx * dx + dy * dy) / (2 * s * s));
  };
  EXPECT_NEAR(test::adaptiveSimpson2D(f, 0, 0.1, 0, 0.1, 1e-10), 2 * M_PI * s * s, 1e-9);
}

TEST(Chi2Framework, CosineSamplerPassesAgainstCosinePdf) {
  auto sample = [](Pcg32& rng) -> std::optional<Vec3> { return sampleCosineHemisphere(rng.uniform2()); };
  const Chi2Result r = chi2TestSphere(sample, [](const Vec3& w) { return cosineHemispherePdfW(w.z); });
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(Chi2Framework, CosineSamplerFailsAgainstUniformHemispherePdf) {
  auto sample = [](Pcg32& rng) -> std::optional<Vec3> { return sampleCosineHemisphere(rng.uniform2()); };
  const Chi2Result r =
      chi2TestSphere(sample, [](const Vec3& w) { return w.z > 0 ? double(uniformHemispherePdfW()) : 0.0; });
  EXPECT_FALSE(r.passed) << r.message;
  EXPECT_LT(r.pValue, 1e-6) << r.message;
}

TEST(Chi2Framework, SubDensityWithAbsorptionPassesAndWrongAbsorptionFails) {
  // Uniform sphere sampler that absorbs 30% of the time: sub-density 0.7 / (4 pi).
  auto sample = [](Pcg32& rng) -> std::optional<Vec3> {
    if (rng.uniform() < 0.3f) return std::nullopt;
    return sampleUniformSphere(rng.uniform2());
  };
  const Chi2Result ok = chi2TestSphere(sample, [](const Vec3&) { return 0.7 * kInv4Pi; });
  EXPECT_TRUE(ok.passed) << ok.message;
  const Chi2Result bad = chi2TestSphere(sample, [](const Vec3&) { return 0.65 * kInv4Pi; });
  EXPECT_FALSE(bad.passed) << bad.message;
}

TEST(Chi2Framework, SamplesWhereDensityIsZeroFail) {
  auto sample = [](Pcg32& rng) -> std::optional<Vec3> { return sampleUniformSphere(rng.uniform2()); };
  const Chi2Result r = chi2TestSphere(sample, [](const Vec3& w) { return w.z > 0 ? 2.0 * kInv4Pi : 0.0; });
  EXPECT_FALSE(r.passed) << r.message;
}

TEST(Chi2Framework, TwoDimensionalTest) {
  // Density p(x, y) = 2x on [0,1]x[0,2] / 2 (x by inversion: x = sqrt(u)).
  auto sample = [](Pcg32& rng) -> std::optional<Vec2> {
    return Vec2(std::sqrt(rng.uniform()), 2 * rng.uniform());
  };
  const Chi2Result ok = chi2Test2D(sample, [](Vec2 p) { return double(p.x); }, {0, 0}, {1, 2}, 10, 10, 100000);
  EXPECT_TRUE(ok.passed) << ok.message;
  const Chi2Result bad = chi2Test2D(sample, [](Vec2) { return 0.5; }, {0, 0}, {1, 2}, 10, 10, 100000);
  EXPECT_FALSE(bad.passed) << bad.message;
}


// ---------------------------------------------------------------------------------------------------
// Fixtures: BSDF descriptions and directions
// ---------------------------------------------------------------------------------------------------
using Type = BsdfDesc::Type;

BsdfDesc makeDesc(Type t, const std::string& id) {
  BsdfDesc d;
  d.type = t;
  d.id = id;
  d.intIOR = 1.5f;
  d.extIOR = 1.0f;
  d.reflectance.value = Color(0.6f, 0.5f, 0.3f);
  d.eta = Color(0.2f, 0.92f, 1.1f);  // copper-like
  d.k = Color(3.9f, 2.45f, 2.14f);
  return d;
}

struct Case {
  std::string name;
  SceneDesc scene;  // holds nested BSDFs (twosided)
  BsdfDesc desc;
  std::vector<float> cosines;  // incident cos(theta) of wo to test
  std::unique_ptr<Bsdf> bsdf() const { return makeBsdf(scene, desc); }
};

const char* distName(MicrofacetType t) { return t == MicrofacetType::GGX ? "ggx" : "beckmann"; }

Vec3 dirFromCos(float c, float phi = 0.7f) {
  const float s = std::sqrt(std::fmax(0.0f, 1 - c * c));
  return {s * std::cos(phi), s * std::sin(phi), c};
}

// Every non-delta configuration, with white parameters when `white` (for the furnace test).
std::vector<Case> nonDeltaCases(bool white = false) {
  std::vector<Case> cases;
  const std::vector<float> front = {0.9f, 0.5f, 0.1f};
  const std::vector<float> both = {0.9f, 0.5f, 0.1f, -0.9f, -0.5f, -0.1f};
  auto whiten = [&](BsdfDesc& d) {
    if (!white) return;
    d.reflectance.value = Color(1.0f);
    d.specularReflectance = d.specularTransmittance = Color(1.0f);
    d.mirror = true;
  };
  {
    Case c{"diffuse", {}, makeDesc(Type::Diffuse, "diffuse"), front};
    whiten(c.desc);
    cases.push_back(std::move(c));
  }
  {
    Case c{"twosided(diffuse)", {}, makeDesc(Type::TwoSided, "twosided"), {-0.9f, -0.5f, -0.1f, 0.5f}};
    c.scene.bsdfs.push_back(makeDesc(Type::Diffuse, "inner"));
    whiten(c.scene.bsdfs.back());
    c.desc.nested = 0;
    cases.push_back(std::move(c));
  }
  for (bool nonlinear : {false, true}) {
    Case c{nonlinear ? "plastic(nonlinear)" : "plastic", {}, makeDesc(Type::Plastic, "plastic"), front};
    c.desc.nonlinear = nonlinear;
    whiten(c.desc);
    cases.push_back(std::move(c));
  }
  for (MicrofacetType dist : {MicrofacetType::GGX, MicrofacetType::Beckmann})
    for (float alpha : {0.05f, 0.2f, 0.6f}) {
      const std::string suffix = std::string("(") + distName(dist) + ", alpha " + std::to_string(alpha).substr(0, 4) + ")";
      for (Type t : {Type::RoughConductor, Type::RoughDielectric, Type::RoughPlastic}) {
        const char* base = t == Type::RoughConductor ? "roughconductor" : t == Type::RoughDielectric ? "roughdielectric" : "roughplastic";
        Case c{base + suffix, {}, makeDesc(t, base), t == Type::RoughDielectric ? both : front};
        c.desc.distribution = dist;
        c.desc.alpha = alpha;
        whiten(c.desc);
        cases.push_back(std::move(c));
      }
    }
  return cases;
}

std::vector<Case> casesMatching(const std::string& prefix) {
  std::vector<Case> out;
  for (Case& c : nonDeltaCases())
    if (c.name.rfind(prefix, 0) == 0) out.push_back(std::move(c));
  return out;
}

// All chi-square tests of this file share one Sidak-corrected significance level.
constexpr int kChi2TestCount = 100;
constexpr int kChi2Samples = 100000;

// Chi-square fit of sample() (non-delta outcomes only) against pdf() for every incident angle.
void chi2Family(const std::string& prefix) {
  const std::vector<Case> cases = casesMatching(prefix);
  ASSERT_FALSE(cases.empty()) << prefix;
  for (const Case& c : cases) {
    const auto bsdf = c.bsdf();
    for (float cosO : c.cosines) {
      const Vec3 wo = dirFromCos(cosO);
      const BsdfQuery q{{0.3f, 0.6f}, TransportMode::Radiance};
      auto sampler = [&](Pcg32& rng) -> std::optional<Vec3> {
        const float uc = rng.uniform();
        const Vec2 ud = rng.uniform2();
        const std::optional<BsdfSample> s = bsdf->sample(wo, uc, ud, q);
        if (!s || s->delta) return std::nullopt;
        return s->wi;
      };
      auto pdf = [&](const Vec3& wi) { return double(bsdf->pdf(wo, wi, q)); };
      // Narrow lobes get finer bins and more samples so that the lobe spans enough cells.
      const bool narrow = c.desc.type != Type::Diffuse && c.desc.type != Type::TwoSided &&
                          c.desc.type != Type::Plastic && c.desc.alpha <= 0.05f;
      const test::Chi2Result r = test::chi2TestSphere(sampler, pdf, narrow ? 40 : 20, narrow ? 80 : 40,
                                                      narrow ? 2 * kChi2Samples : kChi2Samples, 0.01,
                                                      kChi2TestCount, 17);
      EXPECT_TRUE(r.passed) << c.name << " at cos(theta_o) = " << cosO << ": " << r.message;
    }
  }
}

TEST(BsdfChi2, Diffuse) { chi2Family("diffuse"); }
TEST(BsdfChi2, TwoSided) { chi2Family("twosided"); }
TEST(BsdfChi2, PlasticDiffusePart) { chi2Family("plastic"); }
TEST(BsdfChi2, RoughConductor) { chi2Family("roughconductor"); }
TEST(BsdfChi2, RoughDielectric) { chi2Family("roughdielectric"); }
TEST(BsdfChi2, RoughPlastic) { chi2Family("roughplastic"); }

// ---------------------------------------------------------------------------------------------------
// Per-sample consistency: pdf(wo, wi) == pdfW, eval == f, pdf(wi, wo) == pdfRevW
// ---------------------------------------------------------------------------------------------------
bool close(float a, float b, float rel = 2e-3f, float abs = 1e-6f) {
  return std::fabs(a - b) <= rel * std::fmax(std::fabs(a), std::fabs(b)) + abs;
}

TEST(BsdfConsistency, SampleMatchesEvalAndPdf) {
  for (const Case& c : nonDeltaCases()) {
    const auto bsdf = c.bsdf();
    for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance})
      for (float cosO : c.cosines) {
        const Vec3 wo = dirFromCos(cosO);
        const BsdfQuery q{{0.3f, 0.6f}, mode};
        Pcg32 rng(5, 11);
        int bad = 0, valid = 0;
        std::string first;
        for (int i = 0; i < 2000; ++i) {
          const float uc = rng.uniform();
          const Vec2 ud = rng.uniform2();
          const std::optional<BsdfSample> s = bsdf->sample(wo, uc, ud, q);
          if (!s) continue;
          if (s->delta) {
            if (!(s->pdfW > 0 && s->pdfW <= 1)) ++bad;
            continue;
          }
          ++valid;
          const float pdf = bsdf->pdf(wo, s->wi, q), pdfRev = bsdf->pdf(s->wi, wo, q);
          const Color f = bsdf->eval(wo, s->wi, q);
          const bool ok = s->pdfW > 0 && std::isfinite(s->pdfW) && s->f.isFinite() && close(pdf, s->pdfW) &&
                          close(pdfRev, s->pdfRevW) && close(f.r, s->f.r) && close(f.g, s->f.g) &&
                          close(f.b, s->f.b) && std::fabs(length(s->wi) - 1) < 1e-4f;
          if (!ok && bad++ == 0)
            first = "pdf " + std::to_string(pdf) + " vs pdfW " + std::to_string(s->pdfW) + ", pdfRev " +
                    std::to_string(pdfRev) + " vs " + std::to_string(s->pdfRevW) + ", eval.r " +
                    std::to_string(f.r) + " vs f.r " + std::to_string(s->f.r);
        }
        EXPECT_GT(valid, 100) << c.name << " cos " << cosO;
        EXPECT_EQ(bad, 0) << c.name << " cos " << cosO << " mode " << int(mode) << ": first mismatch: " << first;
      }
  }
}

// Bsdf::reads(): the path samplers do not read the numbers a BSDF says it ignores (bsdf_numbers.h), so
// sample() must return the same, bit for bit, whatever they hold; and the flags must be those of the
// BSDF's lobes (a diffuse surface and a mirror each drop numbers: the test is not vacuous).
bool sameSample(const std::optional<BsdfSample>& a, const std::optional<BsdfSample>& b) {
  if (!a || !b) return !a && !b;
  return a->wi.x == b->wi.x && a->wi.y == b->wi.y && a->wi.z == b->wi.z && a->f.r == b->f.r && a->f.g == b->f.g &&
         a->f.b == b->f.b && a->pdfW == b->pdfW && a->pdfRevW == b->pdfRevW && a->delta == b->delta && a->eta == b->eta;
}

TEST(BsdfReads, UnreadNumbersDoNotChangeTheSample) {
  std::vector<Case> cases = nonDeltaCases();
  const std::vector<float> both = {0.9f, 0.5f, 0.1f, -0.9f, -0.5f, -0.1f};
  for (Type t : {Type::Dielectric, Type::ThinDielectric, Type::Conductor})
    cases.push_back(Case{t == Type::Dielectric ? "dielectric" : t == Type::ThinDielectric ? "thindielectric" : "conductor",
                         {}, makeDesc(t, "delta"), both});
  {
    Case c{"twosided(conductor)", {}, makeDesc(Type::TwoSided, "twosided"), both};
    c.scene.bsdfs.push_back(makeDesc(Type::Conductor, "inner"));
    c.desc.nested = 0;
    cases.push_back(std::move(c));
  }
  int withoutComponent = 0, withoutDirection = 0;
  for (const Case& c : cases) {
    const auto bsdf = c.bsdf();
    const BsdfReads r = bsdf->reads();
    const Type t = c.desc.type == Type::TwoSided ? c.scene.bsdfs[0].type : c.desc.type;
    // The lobes: one lobe reads no uComponent; a Dirac lobe no uDir.
    const bool oneLobe = t == Type::Diffuse || t == Type::Conductor || t == Type::RoughConductor;
    const bool dirac = t == Type::Conductor || t == Type::Dielectric || t == Type::ThinDielectric;
    EXPECT_EQ(r.component, !oneLobe) << c.name;
    EXPECT_EQ(r.direction, !dirac) << c.name;
    withoutComponent += !r.component;
    withoutDirection += !r.direction;
    Pcg32 rng(7, 3);
    int sampled = 0;
    for (float cosO : c.cosines)
      for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
        const Vec3 wo = dirFromCos(cosO);
        const BsdfQuery q{{0.3f, 0.6f}, mode};
        for (int i = 0; i < 300; ++i) {
          const float uc = rng.uniform(), uc2 = rng.uniform();
          const Vec2 ud = rng.uniform2(), ud2 = rng.uniform2();
          const std::optional<BsdfSample> s = bsdf->sample(wo, uc, ud, q);
          sampled += s.has_value();
          if (!r.component) {
            EXPECT_TRUE(sameSample(s, bsdf->sample(wo, uc2, ud, q))) << c.name << " reads uComponent";
          }
          if (!r.direction) {
            EXPECT_TRUE(sameSample(s, bsdf->sample(wo, uc, ud2, q))) << c.name << " reads uDir";
          }
        }
      }
    EXPECT_GT(sampled, 0) << c.name;
  }
  EXPECT_GE(withoutComponent, 3);
  EXPECT_GE(withoutDirection, 3);
}

// ---------------------------------------------------------------------------------------------------
// Reciprocity (Veach 1997, sec. 5.3)
// ---------------------------------------------------------------------------------------------------
TEST(BsdfReciprocity, ReflectionSymmetricAndRefractionAdjoint) {
  const BsdfQuery rad{{0.3f, 0.6f}, TransportMode::Radiance}, imp{{0.3f, 0.6f}, TransportMode::Importance};
  for (const Case& c : nonDeltaCases()) {
    const auto bsdf = c.bsdf();
    Pcg32 rng(3, 9);
    int bad = 0, nonzeroTransmit = 0, nonzeroReflect = 0;
    std::string first;
    for (int i = 0; i < 4000; ++i) {
      const Vec3 wo = sampleUniformSphere(rng.uniform2()), wi = sampleUniformSphere(rng.uniform2());
      if (std::fabs(wo.z) < 0.02f || std::fabs(wi.z) < 0.02f) continue;
      const float etaO = wo.z > 0 ? c.desc.extIOR : c.desc.intIOR, etaI = wi.z > 0 ? c.desc.extIOR : c.desc.intIOR;
      for (int ch = 0; ch < 3; ++ch) {
        const float fRad = bsdf->eval(wo, wi, rad)[ch], fRadT = bsdf->eval(wi, wo, rad)[ch];
        const float fImp = bsdf->eval(wo, wi, imp)[ch], fImpT = bsdf->eval(wi, wo, imp)[ch];
        bool ok;
        if (wo.z * wi.z > 0) {
          ok = close(fRad, fRadT) && close(fImp, fImpT) && close(fRad, fImp);
          nonzeroReflect += fRad > 0;
        } else {
          // Adjoint: f*(wo, wi) = f(wi, wo); generalized reciprocity f(wo,wi)/eta_o^2 = f(wi,wo)/eta_i^2 (eq. 5.14).
          ok = close(fRad, fImpT) && close(fRad / (etaO * etaO), fRadT / (etaI * etaI));
          nonzeroTransmit += fRad > 0;
        }
        if (!ok && bad++ == 0)
          first = "wo.z " + std::to_string(wo.z) + " wi.z " + std::to_string(wi.z) + ": rad " + std::to_string(fRad) +
                  " radT " + std::to_string(fRadT) + " imp " + std::to_string(fImp) + " impT " + std::to_string(fImpT);
      }
    }
    EXPECT_EQ(bad, 0) << c.name << ": " << first;
    EXPECT_GT(nonzeroReflect, 0) << c.name;
    if (c.desc.type == Type::RoughDielectric) {
      EXPECT_GT(nonzeroTransmit, 0) << c.name;
    }
  }
}

// ---------------------------------------------------------------------------------------------------
// White furnace: the directional albedo E[f |cos| / pdf] never exceeds one
// ---------------------------------------------------------------------------------------------------
struct AlbedoEstimate { double mean, stdErr; };

AlbedoEstimate albedoBySampling(const Bsdf& b, const Vec3& wo, TransportMode mode, int ch, int n = 20000) {
  Pcg32 rng(21, 4);
  const BsdfQuery q{{0.3f, 0.6f}, mode};
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const float uc = rng.uniform();
    const Vec2 ud = rng.uniform2();
    const std::optional<BsdfSample> s = b.sample(wo, uc, ud, q);
    double w = 0;
    if (s && s->pdfW > 0) w = double(s->f[ch]) * std::fabs(s->wi.z) / s->pdfW;
    sum += w;
    sum2 += w * w;
  }
  const double mean = sum / n, var = std::max(0.0, sum2 / n - mean * mean);
  return {mean, std::sqrt(var / n)};
}

TEST(BsdfFurnace, WhiteAlbedoAtMostOne) {
  std::vector<Case> cases = nonDeltaCases(/*white=*/true);
  for (Type t : {Type::Dielectric, Type::ThinDielectric, Type::Conductor}) {
    Case c{t == Type::Dielectric ? "dielectric" : t == Type::ThinDielectric ? "thindielectric" : "conductor(mirror)",
           {}, makeDesc(t, "delta"), {0.9f, 0.5f, 0.1f, -0.5f}};
    c.desc.mirror = true;
    if (t == Type::Conductor) c.cosines = {0.9f, 0.5f, 0.1f};
    cases.push_back(std::move(c));
  }
  for (const Case& c : cases) {
    const auto bsdf = c.bsdf();
    for (float cosO : c.cosines) {
      const AlbedoEstimate a = albedoBySampling(*bsdf, dirFromCos(cosO), TransportMode::Importance, 1);
      EXPECT_LE(a.mean, 1 + 3 * a.stdErr + 1e-4) << c.name << " cos " << cosO << " albedo " << a.mean << " +- " << a.stdErr;
      EXPECT_GT(a.mean, 0.0) << c.name << " cos " << cosO;
      // Rough plastic is built so that albedo = specR R + rho' T = 1 for white parameters, up to the
      // accuracy of its tabulated R (stratified quadrature, ~1e-3).
      if (c.desc.type == Type::RoughPlastic) {
        EXPECT_NEAR(a.mean, 1.0, 3 * a.stdErr + 5e-3) << c.name << " cos " << cosO;
      }
      // Lossless models: white diffuse, smooth dielectric (R + T = 1 in importance mode), thin slab, mirror.
      if (c.name == "diffuse" || c.name == "dielectric" || c.name == "thindielectric" || c.name == "conductor(mirror)" ||
          c.name == "twosided(diffuse)") {
        EXPECT_NEAR(a.mean, 1.0, 1e-4) << c.name << " cos " << cosO;
      }
    }
  }
}

TEST(BsdfFurnace, DielectricEveryImportanceSampleCarriesUnitWeight) {
  // R + T = 1 exactly: in importance mode every sample's weight f |cos| / pdf is one.
  const auto bsdf = makeBsdf({}, makeDesc(Type::Dielectric, "glass"));
  Pcg32 rng(1, 1);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 wo = sampleUniformSphere(rng.uniform2());
    if (std::fabs(wo.z) < 1e-3f) continue;
    const auto s = bsdf->sample(wo, rng.uniform(), rng.uniform2(), {{0, 0}, TransportMode::Importance});
    ASSERT_TRUE(s.has_value());
    EXPECT_NEAR(s->f.g * std::fabs(s->wi.z) / s->pdfW, 1.0, 1e-4);
  }
}

// ---------------------------------------------------------------------------------------------------
// Delta BSDFs
// ---------------------------------------------------------------------------------------------------
// Textbook Fresnel (double precision), light from medium n1 into n2 at cos(theta_1) = c1.
double fresnelReference(double c1, double n1, double n2) {
  const double s1 = std::sqrt(1 - c1 * c1), s2 = n1 / n2 * s1;
  if (s2 >= 1) return 1;
  const double c2 = std::sqrt(1 - s2 * s2);
  const double rs = (n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2), rp = (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2);
  return 0.5 * (rs * rs + rp * rp);
}

TEST(Fresnel, DielectricMatchesTextbookAndIsSymmetric) {
  for (double c : {1.0, 0.9, 0.7071, 0.5, 0.2, 0.05}) {
    EXPECT_NEAR(fresnelDielectric(float(c), 1.5f), fresnelReference(c, 1.0, 1.5), 1e-5) << c;
    EXPECT_NEAR(fresnelDielectric(float(-c), 1.5f), fresnelReference(c, 1.5, 1.0), 1e-5) << c;
    float cosT;
    const float F = fresnelDielectric(float(c), 1.5f, &cosT);
    EXPECT_LT(cosT, 0);
    // Stokes: the reflectance is the same from the other side at the refracted angle.
    EXPECT_NEAR(fresnelDielectric(cosT, 1.5f), F, 1e-5);
  }
  EXPECT_NEAR(fresnelDielectric(1, 1.5f), 0.04, 1e-6);  // ((n-1)/(n+1))^2
  EXPECT_EQ(fresnelDielectric(-0.3f, 1.5f), 1.0f);       // beyond the critical angle (cos 0.745)
  // Conductor at normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
  EXPECT_NEAR(fresnelConductor1(1, 0.2f, 3.9f), (0.64 + 15.21) / (1.44 + 15.21), 1e-5);
  // Diffuse Fresnel reflectance identity: 1 - Fdr(eta) = eta^2 (1 - Fdr(1/eta)).
  EXPECT_NEAR(1 - fresnelDiffuseReflectance(1.5f), 2.25 * (1 - fresnelDiffuseReflectance(1 / 1.5f)), 1e-4);
}

// Counts how often sample() chooses reflection; binomial test against the expected probability.
void expectChoiceProbability(const Bsdf& b, const Vec3& wo, double pReflect, const std::string& what) {
  Pcg32 rng(99, 2);
  const int n = 20000;
  int reflections = 0;
  for (int i = 0; i < n; ++i) {
    const auto s = b.sample(wo, rng.uniform(), rng.uniform2(), {{0, 0}, TransportMode::Radiance});
    if (s && s->delta && s->wi.z * wo.z > 0) ++reflections;
  }
  const double sigma = std::sqrt(pReflect * (1 - pReflect) / n);
  EXPECT_NEAR(double(reflections) / n, pReflect, 4 * sigma + 1e-9) << what;
}

TEST(DeltaBsdf, DielectricDirectionsFresnelAndSnell) {
  const auto glass = makeBsdf({}, makeDesc(Type::Dielectric, "glass"));
  EXPECT_TRUE(glass->isDelta());
  for (float c : {0.9f, 0.5f, 0.1f, -0.9f, -0.8f, -0.5f}) {
    const Vec3 wo = dirFromCos(c);
    const double n1 = c > 0 ? 1.0 : 1.5, n2 = c > 0 ? 1.5 : 1.0;
    const double F = fresnelReference(std::fabs(c), n1, n2);
    expectChoiceProbability(*glass, wo, F, "dielectric cos " + std::to_string(c));
    // Reflection: uComponent = 0 always reflects (F > 0).
    const auto r = glass->sample(wo, 0.0f, {0.5f, 0.5f}, {});
    ASSERT_TRUE(r.has_value());
    EXPECT_NEAR(r->wi.x, -wo.x, 1e-6);
    EXPECT_NEAR(r->wi.y, -wo.y, 1e-6);
    EXPECT_NEAR(r->wi.z, wo.z, 1e-6);
    EXPECT_NEAR(r->pdfW, F, 1e-5);
    EXPECT_EQ(r->eta, 1.0f);
    if (F >= 1) continue;  // total internal reflection
    // Transmission: Snell's law n1 sin1 = n2 sin2, opposite azimuth, other side, radiance scaled by (n1/n2)^2.
    const auto t = glass->sample(wo, kOneMinusEpsilon, {0.5f, 0.5f}, {{0, 0}, TransportMode::Radiance});
    ASSERT_TRUE(t.has_value());
    EXPECT_LT(t->wi.z * wo.z, 0);
    const double sin1 = std::sqrt(1 - double(c) * c), sin2 = std::sqrt(1 - double(t->wi.z) * t->wi.z);
    EXPECT_NEAR(n1 * sin1, n2 * sin2, 1e-5);
    EXPECT_NEAR(t->wi.x * wo.y - t->wi.y * wo.x, 0, 1e-6);  // in the plane of incidence
    EXPECT_LT(t->wi.x * wo.x + t->wi.y * wo.y, 0);           // on the other side of the normal
    EXPECT_NEAR(t->eta, n2 / n1, 1e-6);
    EXPECT_NEAR(t->pdfW, 1 - F, 1e-5);
    EXPECT_NEAR(t->pdfRevW, 1 - F, 1e-5);
    EXPECT_NEAR(t->f.r * std::fabs(t->wi.z) / t->pdfW, (n1 / n2) * (n1 / n2), 1e-4);
    const auto ti = glass->sample(wo, kOneMinusEpsilon, {0.5f, 0.5f}, {{0, 0}, TransportMode::Importance});
    EXPECT_NEAR(ti->f.r * std::fabs(ti->wi.z) / ti->pdfW, 1.0, 1e-5);
  }
  EXPECT_TRUE(glass->eval(dirFromCos(0.5f), dirFromCos(-0.5f), {}).isBlack());
  EXPECT_EQ(glass->pdf(dirFromCos(0.5f), dirFromCos(0.5f, 0.7f + kPi), {}), 0.0f);
}

TEST(DeltaBsdf, ThinDielectricSlabReflectance) {
  const auto slab = makeBsdf({}, makeDesc(Type::ThinDielectric, "slab"));
  for (float c : {0.9f, 0.5f, 0.1f, -0.5f}) {
    const double R = fresnelReference(std::fabs(c), 1.0, 1.5), T = 1 - R;
    const double Rslab = R + T * T * R / (1 - R * R);
    expectChoiceProbability(*slab, dirFromCos(c), Rslab, "thindielectric cos " + std::to_string(c));
    const auto t = slab->sample(dirFromCos(c), kOneMinusEpsilon, {0.5f, 0.5f}, {});
    ASSERT_TRUE(t.has_value());
    const Vec3 expected = -dirFromCos(c);
    EXPECT_NEAR(t->wi.x, expected.x, 1e-6);
    EXPECT_NEAR(t->wi.z, expected.z, 1e-6);
    EXPECT_EQ(t->eta, 1.0f);
  }
}

TEST(DeltaBsdf, ConductorReflectsWithConductorFresnel) {
  BsdfDesc d = makeDesc(Type::Conductor, "copper");
  d.specularReflectance = Color(0.9f);
  const auto cu = makeBsdf({}, d);
  for (float c : {1.0f, 0.6f, 0.2f}) {
    const Vec3 wo = dirFromCos(c);
    const auto s = cu->sample(wo, 0.3f, {0.1f, 0.9f}, {});
    ASSERT_TRUE(s.has_value());
    EXPECT_TRUE(s->delta);
    EXPECT_NEAR(s->wi.x, -wo.x, 1e-6);
    EXPECT_NEAR(s->wi.z, wo.z, 1e-6);
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(s->f[ch] * s->wi.z / s->pdfW, 0.9f * fresnelConductor1(c, d.eta[ch], d.k[ch]), 1e-5);
  }
  EXPECT_FALSE(cu->sample(dirFromCos(-0.5f), 0.3f, {0.1f, 0.9f}, {}).has_value());  // one-sided
}

TEST(DeltaBsdf, PlasticSpecularChoiceAndWeight) {
  BsdfDesc d = makeDesc(Type::Plastic, "plastic");
  const auto plastic = makeBsdf({}, d);
  const float dLum = luminance(d.reflectance.value), sLum = luminance(d.specularReflectance.value);
  const float w = sLum / (dLum + sLum);
  for (float c : {0.9f, 0.5f, 0.1f}) {
    const Vec3 wo = dirFromCos(c);
    const double F = fresnelReference(c, 1.0, 1.5);
    const double pSpec = F * w / (F * w + (1 - F) * (1 - w));
    expectChoiceProbability(*plastic, wo, pSpec, "plastic cos " + std::to_string(c));
    const auto s = plastic->sample(wo, 0.0f, {0.5f, 0.5f}, {});
    ASSERT_TRUE(s && s->delta);
    EXPECT_NEAR(s->wi.x, -wo.x, 1e-6);
    EXPECT_NEAR(s->f.r * s->wi.z / s->pdfW, F / pSpec, 1e-4);
  }
  EXPECT_FALSE(plastic->isDelta());
}

// ---------------------------------------------------------------------------------------------------
// Microfacet distributions: normalization of D and of the visible-normal density
// ---------------------------------------------------------------------------------------------------
TEST(Microfacet, DistributionAndVisibleNormalsAreNormalized) {
  for (MicrofacetType t : {MicrofacetType::GGX, MicrofacetType::Beckmann})
    for (float alpha : {0.1f, 0.5f, 1.0f}) {
      const Microfacet mf(t, alpha);
      auto onSphere = [](double z, double phi) {
        const double s = std::sqrt(std::max(0.0, 1 - z * z));
        return Vec3(float(s * std::cos(phi)), float(s * std::sin(phi)), float(z));
      };
      const double projected =
          test::adaptiveSimpson2D([&](double z, double phi) { return mf.D(onSphere(z, phi)) * z; }, 0, 1, 0, 2 * M_PI, 1e-7);
      EXPECT_NEAR(projected, 1.0, 2e-3) << distName(t) << " alpha " << alpha;
      for (float c : {0.9f, 0.3f}) {
        const Vec3 v = dirFromCos(c);
        const double visible = test::adaptiveSimpson2D(
            [&](double z, double phi) { return mf.pdfVisible(v, onSphere(z, phi)); }, 0, 1, 0, 2 * M_PI, 1e-7);
        EXPECT_NEAR(visible, 1.0, 2e-3) << distName(t) << " alpha " << alpha << " cos " << c;
      }
    }
}

// ---------------------------------------------------------------------------------------------------
// Textures
// ---------------------------------------------------------------------------------------------------
TEST(Texture, CheckerboardFollowsMitsuba) {
  TextureDesc d;
  d.type = TextureDesc::Type::Checkerboard;
  d.color0 = Color(1, 0, 0);
  d.color1 = Color(0, 0, 1);
  const auto tex = makeTexture(d, "test");
  EXPECT_EQ(tex->eval({0.1f, 0.1f}).r, 1.0f);   // int(0.2)+int(0.2) = 0: color0
  EXPECT_EQ(tex->eval({0.6f, 0.1f}).b, 1.0f);   // 1 + 0: color1
  EXPECT_EQ(tex->eval({0.6f, 0.7f}).r, 1.0f);   // 1 + 1: color0
  EXPECT_EQ(tex->eval({1.1f, 0.1f}).r, 1.0f);   // 2 + 0: color0
  d.uvScale = {2, 1};                            // uv' = (2u, v)
  const auto scaled = makeTexture(d, "test");
  EXPECT_EQ(scaled->eval({0.3f, 0.1f}).b, 1.0f);  // int(1.2) = 1
  EXPECT_NEAR(tex->average().r, 0.5f, 1e-6f);
}

TEST(Texture, BitmapLookupFromPng) {
  // 2x2 image: top row red, green; bottom row blue, white (8-bit).
  const unsigned char px[12] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
  const std::string path =
      (std::filesystem::temp_directory_path() / ("mltfarm_bsdf_test_" + std::to_string(::getpid()) + ".png")).string();
  ASSERT_TRUE(stbi_write_png(path.c_str(), 2, 2, 3, px, 6));
  TextureDesc d;
  d.type = TextureDesc::Type::Bitmap;
  d.filename = path;
  d.srgb = false;
  const auto raw = makeTexture(d, "test");
  // Texel centres: (u, v) = (0.25, 0.25) is the first texel of the first (top) row.
  const Color red = raw->eval({0.25f, 0.25f}), green = raw->eval({0.75f, 0.25f});
  const Color blue = raw->eval({0.25f, 0.75f}), white = raw->eval({0.75f, 0.75f});
  EXPECT_NEAR(red.r, 1, 1e-6);
  EXPECT_NEAR(red.g, 0, 1e-6);
  EXPECT_NEAR(green.g, 1, 1e-6);
  EXPECT_NEAR(blue.b, 1, 1e-6);
  EXPECT_NEAR(white.r + white.g + white.b, 3, 1e-6);
  // Bilinear halfway between red and green; repeat wrapping.
  const Color mid = raw->eval({0.5f, 0.25f});
  EXPECT_NEAR(mid.r, 0.5, 1e-5);
  EXPECT_NEAR(mid.g, 0.5, 1e-5);
  const Color wrapped = raw->eval({1.25f, -0.75f});
  EXPECT_NEAR(wrapped.r, 1, 1e-5);
  EXPECT_NEAR(wrapped.g, 0, 1e-5);
  EXPECT_NEAR(raw->average().r, 0.5, 1e-6);

  // sRGB decode of 8-bit values.
  const unsigned char grey[3] = {128, 128, 128};
  ASSERT_TRUE(stbi_write_png(path.c_str(), 1, 1, 3, grey, 3));
  d.srgb = true;
  EXPECT_NEAR(makeTexture(d, "test")->eval({0.3f, 0.3f}).g, std::pow((128 / 255.0 + 0.055) / 1.055, 2.4), 1e-5);
  d.srgb = false;
  EXPECT_NEAR(makeTexture(d, "test")->eval({0.3f, 0.3f}).g, 128 / 255.0, 1e-6);
  std::filesystem::remove(path);
}

TEST(Texture, DiffuseUsesTexture) {
  BsdfDesc d = makeDesc(Type::Diffuse, "checker");
  d.reflectance.type = TextureDesc::Type::Checkerboard;
  d.reflectance.color0 = Color(0.8f);
  d.reflectance.color1 = Color(0.2f);
  const auto b = makeBsdf({}, d);
  const Vec3 w = dirFromCos(0.5f);
  EXPECT_NEAR(b->eval(w, w, {{0.1f, 0.1f}, TransportMode::Radiance}).r, 0.8f * kInvPi, 1e-6);
  EXPECT_NEAR(b->eval(w, w, {{0.6f, 0.1f}, TransportMode::Radiance}).r, 0.2f * kInvPi, 1e-6);
  EXPECT_NEAR(b->albedo({0.6f, 0.1f}).r, 0.2f, 1e-6);
}

// ---------------------------------------------------------------------------------------------------
// makeBsdf: errors name the BSDF
// ---------------------------------------------------------------------------------------------------
void expectErrorNaming(const SceneDesc& scene, const BsdfDesc& d, const std::string& needle) {
  try {
    makeBsdf(scene, d);
    ADD_FAILURE() << "no error for " << d.id;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(d.id), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(MakeBsdf, ErrorsNameTheBsdf) {
  BsdfDesc rough = makeDesc(Type::RoughConductor, "badAlpha");
  rough.alpha = 0;
  expectErrorNaming({}, rough, "alpha");
  BsdfDesc glass = makeDesc(Type::Dielectric, "badIor");
  glass.intIOR = -1;
  expectErrorNaming({}, glass, "intIOR");
  BsdfDesc tex = makeDesc(Type::Diffuse, "missingTexture");
  tex.reflectance.type = TextureDesc::Type::Bitmap;
  tex.reflectance.filename = "/nonexistent/texture.png";
  expectErrorNaming({}, tex, "texture.png");
  SceneDesc scene;
  scene.bsdfs.push_back(makeDesc(Type::Dielectric, "inner"));
  BsdfDesc two = makeDesc(Type::TwoSided, "twoGlass");
  two.nested = 0;
  expectErrorNaming(scene, two, "transmissive");
  two.nested = 5;
  expectErrorNaming(scene, two, "index");
}

TEST(MakeBsdf, TwoSidedMirrorsBackSide) {
  SceneDesc scene;
  scene.bsdfs.push_back(makeDesc(Type::Plastic, "inner"));
  BsdfDesc two = makeDesc(Type::TwoSided, "two");
  two.nested = 0;
  const auto b = makeBsdf(scene, two);
  const auto inner = makeBsdf(scene, scene.bsdfs[0]);
  const Vec3 wo = dirFromCos(0.6f), wi = dirFromCos(0.3f, 2.0f);
  const Vec3 woB(wo.x, wo.y, -wo.z), wiB(wi.x, wi.y, -wi.z);
  EXPECT_EQ(b->eval(woB, wiB, {}).r, inner->eval(wo, wi, {}).r);
  EXPECT_GT(b->eval(woB, wiB, {}).r, 0);
  EXPECT_EQ(b->eval(woB, wi, {}).r, 0);
  const auto s = b->sample(woB, 0.0f, {0.2f, 0.2f}, {});  // specular from the back
  ASSERT_TRUE(s && s->delta);
  EXPECT_LT(s->wi.z, 0);
}

}  // namespace
}  // namespace mlt
