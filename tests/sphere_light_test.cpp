// Convex area lights (spheres) sampled by the solid angle they subtend (common/emitter/area_light.cpp,
// (C1)): sampleLi's directions against pdfLi (chi-square over the sphere of directions), uniformity in
// the cone's own coordinates for a light far away (no rings from float cosines), the sample's fields,
// the irradiance against area sampling of the same mesh and against a sphere's closed form, the inverse
// used by reversible-jump MLT, and the cases that keep area sampling (a point inside the bounding sphere,
// a mesh facing inward, no surface to trace), and sampleLiVisible (one ray through the scene for the
// point and its visibility) against sampleLi and a shadow ray on the bundled scenes with sphere lights.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "common/core/rng.h"
#include "common/core/sampling.h"
#include "common/core/transform.h"
#include "common/emitter/make_light.h"
#include "common/interfaces/light.h"
#include "common/render/accel.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"
#include "common/scene/mesh_utils.h"
#include "common/scene/scene_desc.h"
#include "tests/support/chi2.h"
#include "tests/support/mesh_density.h"

namespace mlt {
namespace {

using test::chi2Test2D;
using test::chi2TestSphere;
using test::meshPdfW;

constexpr int kChi2Tests = 4;  // Sidak correction across this file's chi-square tests

// The light's own mesh as a ray target, as RenderScene gives it to the light.
struct OwnSurface final : EmitterSurface {
  explicit OwnSurface(const MeshDesc& m) : accel(std::vector<MeshDesc>{m}) {}
  std::optional<SurfaceHit> intersect(const Ray& r) const override { return accel.intersectMesh(0, r); }
  std::optional<SurfaceHit> firstInScene(const Ray& r) const override { return accel.intersectIfOn(0, r); }
  Accel accel;
};

// A UV sphere under an affine map (an ellipsoid: still convex), centre c, semi-axes (0.5, 0.3, 0.4).
const Vec3 kCenter(0.2f, 1.0f, -0.5f);
MeshDesc ellipsoidLight(int nTheta, int nPhi, Color Le, const Vec3& semiAxes = {0.5f, 0.3f, 0.4f}) {
  MeshDesc m = makeSphere(nTheta, nPhi);
  transformMesh(m, Transform::translate(kCenter) * Transform::scale(semiAxes), true);
  m.name = "ellipsoid light";
  m.emission = Le;
  m.convex = true;
  m.bsdf = 0;
  return m;
}

struct Lights {
  MeshDesc mesh;
  std::unique_ptr<Light> cone, area;  // the same mesh with and without its surface
};
Lights makeLights(const MeshDesc& mesh) {
  Lights l;
  l.mesh = mesh;
  l.cone = makeAreaLight(mesh, std::make_shared<OwnSurface>(mesh));
  l.area = makeAreaLight(mesh);
  return l;
}

TEST(SphereLight, SampleLiMatchesPdfLiOutsideTheBoundingSphere) {
  const Lights l = makeLights(ellipsoidLight(8, 16, Color(2.0f)));
  // The bounding sphere's radius is 0.5 (the largest semi-axis): a near point (0.7 from the centre,
  // cone half-angle ~46 degrees) and a farther one.
  for (const Vec3 ref : {kCenter + Vec3(0.0f, 0.7f, 0.0f), kCenter + Vec3(1.2f, -0.4f, 0.9f)}) {
    float pdfW0 = -1;
    bool constant = true;
    auto r = chi2TestSphere(
        [&](Pcg32& rng) -> std::optional<Vec3> {
          auto s = l.cone->sampleLi(ref, rng.uniform2());
          if (!s) return std::nullopt;
          if (pdfW0 < 0) pdfW0 = s->pdfW;
          constant &= s->pdfW == pdfW0;
          return s->wi;
        },
        [&](const Vec3& w) { return meshPdfW(*l.cone, l.mesh, ref, w); }, 20, 40, 100000, 0.01, kChi2Tests, 11);
    EXPECT_TRUE(r.passed) << "ref (" << ref.x << "," << ref.y << "," << ref.z << "): " << r.message;
    EXPECT_TRUE(constant) << "(C1): one density over the cone";
  }
}

// A light 0.03 wide seen from 60 away: 1 - cos(theta_max) ~ 1.3e-7, below a float's resolution near 1.
// The sampled directions, read back in double in the cone's frame, must still be uniform over the cone.
TEST(SphereLight, NarrowConeIsUniformInItsOwnCoordinates) {
  const Lights l = makeLights(ellipsoidLight(16, 32, Color(1.0f), Vec3(0.03f)));
  const Vec3 ref = kCenter + normalize(Vec3(0.3f, -1.0f, 0.2f)) * 60.0f;
  const Vec3 axis = normalize(kCenter - ref);
  const Frame frame(axis);
  const double sin2 = double(0.03f) * 0.03 / double(distanceSquared(ref, kCenter));
  const double a = sin2 / (1 + std::sqrt(1 - sin2));
  auto r = chi2Test2D(
      [&](Pcg32& rng) -> std::optional<Vec2> {
        auto s = l.cone->sampleLi(ref, rng.uniform2());
        if (!s) return std::nullopt;
        const Vec3 w = frame.toLocal(s->wi);  // in double below: x^2 + y^2 carries the angle
        const double oneMinusCos = (double(w.x) * w.x + double(w.y) * w.y) / (1 + double(w.z));
        // (1 - cos) / a is u.x: uniform on [0, 1). The inscribed mesh leaves the cone's rim (beyond ~0.9
        // for 16 rings) partly unhit, so the test keeps [0, 0.85) and counts the rest as absorbed.
        const double x = oneMinusCos / a;
        if (!(x < 0.85)) return std::nullopt;
        double phi = std::atan2(double(w.y), double(w.x));
        if (phi < 0) phi += 2 * M_PI;
        return Vec2(float(x), float(phi / (2 * M_PI)));
      },
      [](Vec2) { return 1.0; }, Vec2(0, 0), Vec2(0.85f, 1), 17, 8, 100000, 0.01, kChi2Tests, 12);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(SphereLight, SampleFieldsAreConsistent) {
  const Lights l = makeLights(ellipsoidLight(8, 16, Color(1, 2, 3)));
  const Vec3 ref = kCenter + Vec3(0.9f, 0.6f, -0.4f);
  Pcg32 rng(5, 6);
  int misses = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec2 u = rng.uniform2();
    auto s = l.cone->sampleLi(ref, u);
    if (!s) {
      ++misses;
      continue;
    }
    EXPECT_NEAR(length(s->wi), 1.0f, 1e-5f);
    EXPECT_NEAR(dot(normalize(s->pLight - ref), s->wi), 1.0f, 1e-5f);
    EXPECT_LT(dot(s->nLight, s->wi), 0.0f) << "the point faces ref";
    EXPECT_EQ(s->pdfW, l.cone->pdfLi(ref, s->pLight, s->nLight, s->wi));
    EXPECT_NEAR(s->pdfA * distanceSquared(ref, s->pLight) / absDot(s->nLight, s->wi), s->pdfW, 1e-4f * s->pdfW);
    EXPECT_EQ(s->L.b, l.cone->L(s->pLight, s->nLight, s->uv, -s->wi).b);
    // bdpt's factor k: the cone's pdfA over the area sampler's pdfPos (1 / A).
    const float pdfPos = l.area->sampleLi(ref, u)->pdfA;
    EXPECT_NEAR(l.cone->pdfLiOverPdfPos(ref, s->pLight, s->nLight) * pdfPos, s->pdfA, 1e-4f * s->pdfA);
    // The far side of the mesh along the same ray has density 0 and k = 0.
    EXPECT_EQ(l.cone->pdfLi(ref, s->pLight, -s->nLight, s->wi), 0.0f);
    EXPECT_EQ(l.cone->pdfLiOverPdfPos(ref, s->pLight, -s->nLight), 0.0f);
  }
  // The bounding sphere's cone is wider than the ellipsoid (semi-axes 0.3 and 0.4 against the bounding
  // radius 0.5): a part of its directions miss; for a sphere only the rim between the inscribed mesh and
  // the sphere does.
  EXPECT_LT(misses, 4000 / 2);
  const Lights sphere = makeLights(ellipsoidLight(16, 32, Color(1.0f), Vec3(0.4f)));
  int sphereMisses = 0;
  for (int i = 0; i < 4000; ++i) sphereMisses += !sphere.cone->sampleLi(ref, rng.uniform2());
  EXPECT_LT(sphereMisses, 4000 / 25);
}

// E = integral of L cos(theta_ref) dw estimated by both samplers of the same mesh: the same value within
// their combined standard error, and the cone's estimate the less noisy.
TEST(SphereLight, IrradianceAgreesWithAreaSamplingAndIsLessNoisy) {
  const Lights l = makeLights(ellipsoidLight(16, 32, Color(3.0f)));
  for (const Vec3 ref : {kCenter + Vec3(0.0f, 0.8f, 0.1f), kCenter + Vec3(-1.5f, 0.4f, 1.0f), kCenter + Vec3(3, -4, 2)}) {
    const Vec3 n = normalize(kCenter - ref + Vec3(0.2f, 0.1f, 0.0f));  // a surface at ref, tilted off the centre
    auto estimate = [&](const Light& light, uint64_t seed, double* mean, double* se) {
      Pcg32 rng(seed, 1);
      const int N = 200000;
      double sum = 0, sum2 = 0;
      for (int i = 0; i < N; ++i) {
        double v = 0;
        if (auto s = light.sampleLi(ref, rng.uniform2()); s && s->pdfW > 0) v = s->L.r * std::fmax(0.0f, dot(n, s->wi)) / s->pdfW;
        sum += v;
        sum2 += v * v;
      }
      *mean = sum / N;
      *se = std::sqrt(std::fmax(0.0, sum2 / N - *mean * *mean) / N);
    };
    double mc, sc, ma, sa;
    estimate(*l.cone, 21, &mc, &sc);
    estimate(*l.area, 22, &ma, &sa);
    std::printf("ref (%.2f %.2f %.2f): cone %.6f +- %.2e, area %.6f +- %.2e, variance ratio %.1f\n", ref.x, ref.y,
                ref.z, mc, sc, ma, sa, (sa * sa) / (sc * sc));
    EXPECT_LT(std::fabs(mc - ma), 5 * std::hypot(sc, sa));
    EXPECT_GT(sa * sa, 2 * sc * sc) << "the cone should cut the variance at least in half";
  }
}

// A finely tessellated sphere of radius R seen from distance d along the normal of the receiving
// surface: E = pi L (R / d)^2 for the exact sphere; the inscribed mesh subtends a little less.
TEST(SphereLight, IrradianceOfASphereMatchesItsClosedForm) {
  const float R = 0.3f, d = 1.0f, Le = 5.0f;
  const Lights l = makeLights(ellipsoidLight(64, 128, Color(Le), Vec3(R)));
  const Vec3 ref = kCenter + Vec3(0, -d, 0), n(0, 1, 0);
  Pcg32 rng(31, 1);
  const int N = 400000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < N; ++i) {
    double v = 0;
    if (auto s = l.cone->sampleLi(ref, rng.uniform2())) v = s->L.r * std::fmax(0.0f, dot(n, s->wi)) / s->pdfW;
    sum += v;
    sum2 += v * v;
  }
  const double E = sum / N, se = std::sqrt((sum2 / N - E * E) / N);
  const double exact = M_PI * Le * (R / d) * (R / d);
  std::printf("E %.6f +- %.2e, closed form %.6f (ratio %.5f)\n", E, se, exact, E / exact);
  // The 64 x 128 mesh's silhouette lies within 1 - cos(pi / 128) ~ 3e-4 of the sphere's radius.
  EXPECT_LT(E, exact * (1 + 1e-4) + 4 * se);
  EXPECT_GT(E, exact * (1 - 3e-3) - 4 * se);
  EXPECT_LT(se, 1e-3 * exact);
}

// Reversible-jump MLT inverts sampleLi: the numbers that give the point, and its pdfA as the Jacobian.
TEST(SphereLight, InvertSampleLiRoundTrips) {
  const Lights l = makeLights(ellipsoidLight(8, 16, Color(1.0f)));
  const Vec3 ref = kCenter + Vec3(-0.6f, 0.8f, 0.3f);
  Pcg32 rng(41, 2);
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec2 u = rng.uniform2();
    auto s = l.cone->sampleLi(ref, u);
    if (!s) continue;
    const std::optional<Inverse2D> inv = l.cone->invertSampleLi(ref, s->pLight, s->nLight, InverseGamma{});
    ASSERT_TRUE(inv) << "u = (" << u.x << ", " << u.y << ")";
    const float du = std::fabs(inv->u.x - u.x), dv = std::fmin(std::fabs(inv->u.y - u.y), 1 - std::fabs(inv->u.y - u.y));
    EXPECT_LT(du, 1e-4f);
    EXPECT_LT(dv, 1e-4f);
    EXPECT_NEAR(inv->jacobian, s->pdfA, 1e-3f * s->pdfA);
    ++checked;
  }
  EXPECT_GT(checked, 1000);  // the rest missed the ellipsoid
  // A point on the far side cannot be sampled from ref.
  auto s = l.cone->sampleLi(ref, {0.3f, 0.6f});
  ASSERT_TRUE(s);
  EXPECT_FALSE(l.cone->invertSampleLi(ref, s->pLight, -s->nLight, InverseGamma{}));
}

// Inside the bounding sphere (but outside the mesh), for a mesh facing inward, and without a surface to
// trace, the light samples by area: the same samples as the area-only light, bit for bit.
TEST(SphereLight, KeepsAreaSamplingWhereTheConeDoesNotApply) {
  const Lights l = makeLights(ellipsoidLight(8, 16, Color(1.0f)));
  MeshDesc inward = ellipsoidLight(8, 16, Color(1.0f));
  flipMesh(inward);
  const auto inwardCone = makeAreaLight(inward, std::make_shared<OwnSurface>(inward));
  const auto inwardArea = makeAreaLight(inward);
  const Vec3 inside = kCenter + Vec3(0, 0.45f, 0);  // the y semi-axis is 0.3, the bounding radius 0.5
  const Vec3 outside = kCenter + Vec3(1.0f, 0.5f, 0.2f);
  Pcg32 rng(51, 3);
  for (int i = 0; i < 500; ++i) {
    const Vec2 u = rng.uniform2();
    auto a = l.cone->sampleLi(inside, u), b = l.area->sampleLi(inside, u);
    ASSERT_EQ(bool(a), bool(b));
    if (a) {
      EXPECT_EQ(a->pLight.x, b->pLight.x);
      EXPECT_EQ(a->pdfW, b->pdfW);
      EXPECT_EQ(l.cone->pdfLi(inside, a->pLight, a->nLight, a->wi), l.area->pdfLi(inside, a->pLight, a->nLight, a->wi));
      EXPECT_EQ(l.cone->pdfLiOverPdfPos(inside, a->pLight, a->nLight), 1.0f);
    }
    auto c = inwardCone->sampleLi(outside, u), d = inwardArea->sampleLi(outside, u);
    ASSERT_EQ(bool(c), bool(d));
    if (c) {
      EXPECT_EQ(c->pLight.y, d->pLight.y);
      EXPECT_EQ(c->pdfW, d->pdfW);
    }
  }
}

// sampleLiVisible's one ray through the scene against sampleLi followed by the shadow ray pt and bdpt
// traced before, from points on every surface of the two bundled scenes with sphere lights (plates,
// walls and a glass sphere between the points and the lights: many samples blocked). Where both see the
// light the sample must be sampleLi's, bit for bit (the same ray from ref, the same first facet); the
// verdicts may differ only where the two rays leave ref's surface differently (tMin along the ray
// instead of an offset along the normal): a few in a thousand at most.
TEST(SphereLight, VisibleSampleIsSampleLiWithItsShadowRay) {
  for (const char* name : {"glossy-plates", "caustic-mirror"}) {
    SCOPED_TRACE(name);
    const auto scene = RenderScene::build(loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + name + ".xml"));
    Pcg32 rng(7, 11);
    const Vec3 c = scene->center();
    const float r = 0.6f * scene->radius();
    int drawn = 0, both = 0, blocked = 0, differ = 0;
    for (int i = 0; i < 20000; ++i) {
      Ray ray;
      ray.o = c + Vec3(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f) * r;
      ray.d = sampleUniformSphere({rng.uniform(), rng.uniform()});
      const std::optional<SurfaceHit> hit = scene->intersect(ray);
      if (!hit || hit->light >= 0) continue;
      for (const auto& light : scene->lights()) {
        if (!light->liDensityDiffers()) continue;
        const Vec2 u(rng.uniform(), rng.uniform());
        const std::optional<LightLiSample> a = light->sampleLi(hit->p, u);
        const std::optional<LightLiSample> b = light->sampleLiVisible(hit->p, hit->ng, u);
        drawn += a.has_value();
        const bool seen = a && scene->visible(hit->p, hit->ng, a->pLight, a->nLight);
        if (seen != b.has_value()) {
          ++differ;
          continue;
        }
        if (!b) {
          blocked += a.has_value();
          continue;
        }
        ++both;
        EXPECT_TRUE(b->unoccluded);
        EXPECT_EQ(b->pLight.x, a->pLight.x);
        EXPECT_EQ(b->pLight.y, a->pLight.y);
        EXPECT_EQ(b->pLight.z, a->pLight.z);
        EXPECT_EQ(b->nLight.x, a->nLight.x);
        EXPECT_EQ(b->nLight.y, a->nLight.y);
        EXPECT_EQ(b->nLight.z, a->nLight.z);
        EXPECT_EQ(b->pdfW, a->pdfW);
        EXPECT_EQ(b->pdfA, a->pdfA);
        EXPECT_EQ(b->L.r, a->L.r);
      }
    }
    std::printf("%s: %d samples drawn, %d seen by both, %d blocked for both, %d verdicts differ\n", name, drawn,
                both, blocked, differ);
    EXPECT_GT(both, 2000);
    EXPECT_GT(blocked, 250);  // the test covers blocked samples too
    EXPECT_LE(differ, 0.003 * drawn) << "the one-ray visibility disagrees with the shadow ray";
  }
}

}  // namespace
}  // namespace mlt
