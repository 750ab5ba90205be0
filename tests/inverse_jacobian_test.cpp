// The inverses' Jacobians measured directly (Bitterli et al. 2017, sec. 6: "the Jacobian determinant of
// this inverse is equal to the PDF of the sampling technique"): |det du/dx| by central finite differences of
// the inverse itself, in a local orthonormal parametrization of the output (two tangent directions of a
// direction's unit sphere, or of a light's surface), times the width of the discrete choice's interval,
// must equal the pdf the forward routine reports. This does not trust the inverses' reported `jacobian`
// (often the pdf function itself); it checks that the inverse really is the forward routine's CDF.
// Piecewise maps (concentric disk wedges, triangle choice) have kinks where a difference quotient
// straddles two pieces, so the test asks 95% of random points to agree to 1%. Fixed seeds.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/bsdf/bsdfs.h"
#include "common/camera/make_camera.h"
#include "common/core/rng.h"
#include "common/core/sampling.h"
#include "common/core/transform.h"
#include "common/emitter/light_factories.h"
#include "common/emitter/make_light.h"

namespace mlt {
namespace {

// |det| of the 2x2 derivative of u(a, b) at 0 by central differences; nullopt if the inverse fails nearby.
std::optional<double> determinant(const std::function<std::optional<Vec2>(double, double)>& u, double h) {
  const auto ua0 = u(-h, 0), ua1 = u(h, 0), ub0 = u(0, -h), ub1 = u(0, h);
  if (!ua0 || !ua1 || !ub0 || !ub1) return std::nullopt;
  // Periodic coordinates (azimuths) may wrap: take the short way around.
  auto d = [](float a, float b) {
    double x = double(b) - a;
    if (x > 0.5) x -= 1;
    if (x < -0.5) x += 1;
    return x;
  };
  const double j00 = d(ua0->x, ua1->x) / (2 * h), j10 = d(ua0->y, ua1->y) / (2 * h);
  const double j01 = d(ub0->x, ub1->x) / (2 * h), j11 = d(ub0->y, ub1->y) / (2 * h);
  return std::fabs(j00 * j11 - j01 * j10);
}

// The direction w moved by (a, b) along its tangent plane (solid angle da db at a = b = 0).
Vec3 around(const Vec3& w, double a, double b) {
  const Frame f(w);
  return normalize(w + f.s * float(a) + f.t * float(b));
}

struct Tally {
  int total = 0, agree = 0;
  std::string first;
  void add(double measured, double expected, const std::string& what) {
    ++total;
    if (std::fabs(measured - expected) <= 1e-2 * expected) ++agree;
    else if (first.empty()) first = what + ": |du/dx| " + std::to_string(measured) + " vs pdf " + std::to_string(expected);
  }
  void check(const std::string& name, int minTotal) const {
    EXPECT_GE(total, minTotal) << name;
    EXPECT_GE(agree, int(0.95 * total)) << name << ": " << agree << " of " << total << "; " << first;
  }
};

TexturePtr constant(float v) { return std::make_shared<ConstantTexture>(Color(v)); }

// BSDFs whose uDir is one-to-one given the lobe: |det duDir/dwi| * (uComponent interval width) = pdf.
TEST(InverseJacobian, BsdfDirectionsAreTheCdfOfTheirPdf) {
  const Color eta(0.2f, 0.4f, 1.4f), k(3.9f, 2.4f, 1.6f);
  struct Case {
    std::string name;
    std::shared_ptr<Bsdf> bsdf;
    bool twoSidedWo;
  };
  const std::vector<Case> cases = {
      {"diffuse", makeDiffuse(constant(0.5f)), false},
      {"rough_conductor_ggx", makeRoughConductor(MicrofacetType::GGX, 0.3f, nullptr, eta, k, false, constant(1.0f)), false},
      {"rough_conductor_beckmann", makeRoughConductor(MicrofacetType::Beckmann, 0.25f, nullptr, eta, k, false, constant(1.0f)), false},
      {"rough_dielectric_ggx", makeRoughDielectric(MicrofacetType::GGX, 0.3f, nullptr, 1.5f, constant(1.0f), constant(1.0f)), true},
      {"rough_dielectric_beckmann", makeRoughDielectric(MicrofacetType::Beckmann, 0.3f, nullptr, 1.33f, constant(1.0f), constant(1.0f)), true}};
  const BsdfQuery q{Vec2(0.5f, 0.5f), TransportMode::Radiance};
  for (const Case& c : cases) {
    Pcg32 rng(61, 1);
    Tally tally;
    for (int i = 0; i < 3000; ++i) {
      Vec3 wo = sampleCosineHemisphere(rng.uniform2());
      if (c.twoSidedWo && rng.uniform() < 0.5f) wo = -wo;
      const std::optional<BsdfSample> s = c.bsdf->sample(wo, rng.uniform(), rng.uniform2(), q);
      if (!s || !(s->pdfW > 0)) continue;
      InverseGamma g;
      g.pick = 0.5f;
      const std::optional<BsdfSampleInverse> base = c.bsdf->invertSample(wo, s->wi, g, q);
      if (!base) continue;
      // The lobe's interval width: uComponent = a + pick (b - a), so (b - a) = d uComponent / d pick.
      InverseGamma g2 = g;
      g2.pick = 0.75f;
      const std::optional<BsdfSampleInverse> other = c.bsdf->invertSample(wo, s->wi, g2, q);
      if (!other) continue;
      const double width = c.name == "diffuse" || c.name.rfind("rough_conductor", 0) == 0
                               ? 1.0
                               : (double(other->uComponent) - base->uComponent) / 0.25;
      const auto det = determinant(
          [&](double a, double b) -> std::optional<Vec2> {
            const auto inv = c.bsdf->invertSample(wo, around(s->wi, a, b), g, q);
            return inv ? std::optional<Vec2>(inv->uDir) : std::nullopt;
          },
          2e-3);
      if (det) tally.add(*det * width, s->pdfW, c.name);
    }
    tally.check(c.name, 1500);
  }
}

// Area light: u(position) on the surface, |det du/dA| = 1 / A (the triangle choice's width times 1 / area_i).
TEST(InverseJacobian, AreaLightPositionsAreUniformByArea) {
  MeshDesc m;
  m.name = "tent";
  m.positions = {{0, 0, 0}, {3, 0, 0}, {3, 1, 1}, {0, 1, 1}, {3, 0, 2}, {0, 0, 2}};
  m.indices = {0, 1, 2, 0, 2, 3, 3, 2, 4, 3, 4, 5};
  m.emission = Color(1.0f);
  const auto light = makeAreaLight(m);
  Pcg32 rng(62, 1);
  Tally tally;
  const Vec3 ref(1.5f, 5, 1);
  for (int i = 0; i < 3000; ++i) {
    const std::optional<LightLiSample> s = light->sampleLi(ref, rng.uniform2());
    if (!s) continue;
    const Frame f(s->nLight);
    const auto det = determinant(
        [&](double a, double b) -> std::optional<Vec2> {
          const Vec3 p = s->pLight + f.s * float(a) + f.t * float(b);
          const auto inv = light->invertSampleLi(ref, p, s->nLight, InverseGamma{});
          return inv ? std::optional<Vec2>(inv->u) : std::nullopt;
        },
        1e-3);
    if (det) tally.add(*det, s->pdfA, "area light");
  }
  tally.check("area light", 2000);
}

// Constant environment (directions) and spot light (cone) by solid angle.
TEST(InverseJacobian, EmittedDirectionsAreTheCdfOfTheirPdf) {
  auto env = makeConstantEnvironment(Color(1.0f));
  env->preprocess({0, 0, 0}, 5);
  auto spot = makeSpotLight({0, 0, 0}, {0.3f, -1, 0.2f}, Color(1.0f), 40, 10);
  for (Light* light : {env.get(), spot.get()}) {
    Pcg32 rng(63, 1);
    Tally tally;
    for (int i = 0; i < 3000; ++i) {
      const std::optional<LightLeSample> s = light->sampleLe(rng.uniform2(), rng.uniform2());
      if (!s) continue;
      const auto det = determinant(
          [&](double a, double b) -> std::optional<Vec2> {
            const Vec3 w = around(s->ray.d, a, b);
            if (light == env.get()) {  // its emitted origin moves with w: invert the direction via sampleLi
              const auto inv = light->invertSampleLi({0, 0, 0}, -w * 10.0f, w, InverseGamma{});
              return inv ? std::optional<Vec2>(inv->u) : std::nullopt;
            }
            const auto inv = light->invertSampleLe(s->ray.o, s->nLight, w, InverseGamma{});
            return inv ? std::optional<Vec2>(inv->dir.u) : std::nullopt;
          },
          2e-3);
      if (det) tally.add(*det, s->pdfDir, "emitted direction");
    }
    tally.check(light == env.get() ? "environment" : "spot", 2000);
  }
}

// Camera: raster position per steradian of the ray direction (thin lens: for a fixed lens point).
TEST(InverseJacobian, CameraRasterPerSolidAngle) {
  for (bool thin : {false, true}) {
    CameraDesc d;
    d.toWorld = Transform::lookAt({0, 0, -3}, {0, 0, 0}, {0, 1, 0});
    d.fovDeg = 60;
    d.width = 64;
    d.height = 48;
    d.nearClip = 1e-3f;
    if (thin) {
      d.type = CameraDesc::Type::ThinLens;
      d.apertureRadius = 0.2f;
      d.focusDistance = 2.5f;
    }
    const auto cam = makeCamera(d);
    Pcg32 rng(64, 1);
    Tally tally;
    for (int i = 0; i < 3000; ++i) {
      const CameraRay r = cam->generateRay({rng.uniform() * 64, rng.uniform() * 48}, rng.uniform2());
      float pdfPos = 0, pdfDir = 0;
      cam->pdfWe(r.ray, &pdfPos, &pdfDir);
      const auto det = determinant(
          [&](double a, double b) -> std::optional<Vec2> {
            Ray ray = r.ray;
            ray.d = around(r.ray.d, a, b);
            const auto inv = cam->invertGenerateRay(ray, InverseGamma{});
            return inv ? std::optional<Vec2>(Vec2(inv->pRaster.x / 64, inv->pRaster.y / 48)) : std::nullopt;
          },
          1e-3);
      if (det) tally.add(*det, pdfDir, thin ? "thin lens" : "pinhole");
    }
    tally.check(thin ? "thin lens" : "pinhole", 2500);
  }
}

}  // namespace
}  // namespace mlt
