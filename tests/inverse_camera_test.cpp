// Inverses of the cameras' sampling routines (reversible-jump MLT, Bitterli et al. 2017, sec. 6), for a
// pinhole and a thin lens:
//  - generateRay(pRaster, uLens) -> invertGenerateRay -> the same raster position and lens sample
//    regenerate the same ray (1e-4 relative); the raster Jacobian is W H pdfDir (pixels per steradian)
//    and the lens Jacobian pdfPos;
//  - sampleWi(ref, uLens) -> invertSampleWi -> the same lens point; Jacobian pdfPos;
//  - the inverted lens numbers of uniform numbers are uniform (a pinhole's unread uLens is gamma.fill).
// Fixed seeds.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/camera/make_camera.h"
#include "common/core/rng.h"
#include "common/core/transform.h"
#include "tests/support/two_sample_chi2.h"

namespace mlt {
namespace {

CameraDesc camera(bool thinLens) {
  CameraDesc d;
  d.toWorld = Transform::lookAt({0.3f, 1.2f, -4}, {0, 0.8f, 0}, {0.1f, 1, 0});
  d.fovDeg = 50;
  d.width = 96;
  d.height = 64;
  d.nearClip = 1e-3f;
  if (thinLens) {
    d.type = CameraDesc::Type::ThinLens;
    d.apertureRadius = 0.15f;
    d.focusDistance = 3.5f;
  }
  return d;
}

InverseGamma randomGamma(Pcg32& rng) {
  InverseGamma g;
  g.pick = rng.uniform();
  g.fill = rng.uniform2();
  return g;
}
bool relClose(float a, float b, float tol = 1e-4f) { return std::fabs(a - b) <= tol * std::fmax(std::fabs(a), std::fabs(b)); }

TEST(InverseCamera, GenerateRayRoundTripAndJacobians) {
  for (bool thin : {false, true}) {
    SCOPED_TRACE(thin ? "thin lens" : "pinhole");
    const auto cam = makeCamera(camera(thin));
    Pcg32 rng(51, 1);
    int bad = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec2 pRaster(rng.uniform() * cam->width(), rng.uniform() * cam->height());
      const Vec2 uLens = rng.uniform2();
      const CameraRay r = cam->generateRay(pRaster, uLens);
      const std::optional<CameraRayInverse> inv = cam->invertGenerateRay(r.ray, randomGamma(rng));
      float pdfPos = 0, pdfDir = 0;
      cam->pdfWe(r.ray, &pdfPos, &pdfDir);
      bool ok = inv.has_value();
      if (ok) {
        const CameraRay r2 = cam->generateRay(inv->pRaster, inv->lens.u);
        ok = length(r2.ray.o - r.ray.o) <= 1e-4f * 4 && length(r2.ray.d - r.ray.d) <= 1e-4f &&
             std::fabs(inv->pRaster.x - pRaster.x) <= 1e-4f * cam->width() &&
             std::fabs(inv->pRaster.y - pRaster.y) <= 1e-4f * cam->height() &&
             relClose(inv->jacobianRaster, float(cam->width()) * float(cam->height()) * pdfDir) &&
             relClose(inv->lens.jacobian, pdfPos) && (thin || (inv->lens.u.x >= 0 && inv->lens.u.x < 1));
        if (thin) ok = ok && std::fabs(inv->lens.u.x - uLens.x) <= 1e-3f && std::fabs(inv->lens.u.y - uLens.y) <= 1e-3f;
      }
      if (!ok && bad++ < 3) ADD_FAILURE() << "sample " << i << (inv ? "" : " rejected");
    }
  }
}

TEST(InverseCamera, SampleWiRoundTripAndJacobian) {
  for (bool thin : {false, true}) {
    SCOPED_TRACE(thin ? "thin lens" : "pinhole");
    const auto cam = makeCamera(camera(thin));
    Pcg32 rng(52, 1);
    int forward = 0, bad = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec3 ref(rng.uniform() * 4 - 2, rng.uniform() * 3 - 0.5f, rng.uniform() * 3 - 1);
      const std::optional<CameraWiSample> s = cam->sampleWi(ref, rng.uniform2());
      const InverseGamma gamma = randomGamma(rng);
      if (!s) continue;
      ++forward;
      const std::optional<Inverse2D> inv = cam->invertSampleWi(ref, s->pLens, gamma);
      const std::optional<CameraWiSample> s2 = inv ? cam->sampleWi(ref, inv->u) : std::nullopt;
      Ray ray;
      ray.o = s->pLens;
      ray.d = -s->wi;
      float pdfPos = 0, pdfDir = 0;
      cam->pdfWe(ray, &pdfPos, &pdfDir);
      const bool ok = s2 && length(s2->pLens - s->pLens) <= 1e-4f * 4 && relClose(inv->jacobian, pdfPos);
      if (!ok && bad++ < 3) ADD_FAILURE() << "sample " << i << (inv ? "" : " rejected");
    }
    EXPECT_GT(forward, 2000);
  }
}

TEST(InverseCamera, RejectsRaysOffTheFilmOrLens) {
  const auto pin = makeCamera(camera(false)), thin = makeCamera(camera(true));
  Ray behind;
  behind.o = Vec3(0.3f, 1.2f, -4);
  behind.d = Vec3(0, 0, -1);  // away from the view direction
  EXPECT_FALSE(pin->invertGenerateRay(behind, InverseGamma{}));
  Ray offLens;
  offLens.o = Vec3(1.3f, 1.2f, -4);  // 1 unit off a lens of radius 0.15 (and off the pinhole)
  offLens.d = normalize(Vec3(0, 0.8f, 0) - offLens.o);
  EXPECT_FALSE(pin->invertGenerateRay(offLens, InverseGamma{}));
  EXPECT_FALSE(thin->invertGenerateRay(offLens, InverseGamma{}));
}

// The lens numbers (and the raster position scaled to [0,1)) of uniform numbers come back uniform.
TEST(InverseCamera, InverseOfUniformIsUniform) {
  for (bool thin : {false, true}) {
    SCOPED_TRACE(thin ? "thin lens" : "pinhole");
    const auto cam = makeCamera(camera(thin));
    Pcg32 ra(53, 1), rb(53, 2);
    std::vector<float> a, b;
    for (int i = 0; i < 100000; ++i) {
      a.insert(a.end(), {ra.uniform(), ra.uniform(), ra.uniform(), ra.uniform()});
      const Vec2 pRaster(rb.uniform() * cam->width(), rb.uniform() * cam->height());
      const CameraRay r = cam->generateRay(pRaster, rb.uniform2());
      const std::optional<CameraRayInverse> inv = cam->invertGenerateRay(r.ray, randomGamma(rb));
      ASSERT_TRUE(inv);
      b.insert(b.end(), {std::fmin(inv->pRaster.x / cam->width(), kOneMinusEpsilon),
                         std::fmin(inv->pRaster.y / cam->height(), kOneMinusEpsilon), inv->lens.u.x, inv->lens.u.y});
    }
    const test::TwoSampleResult r = test::twoSampleChi2(a, b, 4, 5, 0.01, 2);
    EXPECT_TRUE(r.passed) << r.message;
  }
}

}  // namespace
}  // namespace mlt
