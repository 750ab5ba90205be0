// Cameras (pinhole and thin lens): Mitsuba's orientation conventions and fov_axis, chi-square of the
// directions generateRay produces from uniform raster positions against pdfWe's pdfDir, We integrating
// to one over lens x directions, and round trips generateRay -> point -> rasterPosition / We / sampleWi.
#include <gtest/gtest.h>

#include <cmath>

#include "common/core/sampling.h"
#include "common/camera/make_camera.h"
#include "common/scene/scene_desc.h"
#include "tests/support/chi2.h"

namespace mlt {
namespace {

constexpr int kChi2Tests = 2;

CameraDesc lookingAlongZ(float fovDeg, CameraDesc::FovAxis axis, int w = 64, int h = 48) {
  CameraDesc d;
  d.toWorld = Transform::lookAt({0, 0, 0}, {0, 0, 1}, {0, 1, 0});
  d.fovDeg = fovDeg;
  d.fovAxis = axis;
  d.width = w;
  d.height = h;
  d.nearClip = 1e-3f;
  return d;
}

float deg(float rad) { return rad * 180 / kPi; }

TEST(Camera, MitsubaOrientationIsNotMirrored) {
  const auto cam = makeCamera(lookingAlongZ(60, CameraDesc::FovAxis::X));
  // Mitsuba's lookat: camera +x = up x dir = world +x here, and camera +x is the LEFT of the image.
  auto left = cam->rasterPosition({1, 0, 5});
  auto up = cam->rasterPosition({0, 1, 5});
  ASSERT_TRUE(left && up);
  EXPECT_LT(left->x, 32.0f);
  EXPECT_NEAR(left->y, 24.0f, 1e-3f);
  EXPECT_LT(up->y, 24.0f);  // raster y grows downward
  EXPECT_NEAR(up->x, 32.0f, 1e-3f);
  const CameraRay c = cam->generateRay({32, 24}, {0.5f, 0.5f});
  EXPECT_NEAR(c.ray.d.z, 1.0f, 1e-6f);
  EXPECT_NEAR(c.n.z, 1.0f, 1e-6f);
  const CameraRay l = cam->generateRay({0, 24}, {0.5f, 0.5f});  // left edge: half the horizontal fov
  EXPECT_GT(l.ray.d.x, 0.0f);
  EXPECT_NEAR(deg(std::atan2(l.ray.d.x, l.ray.d.z)), 30.0f, 1e-3f);
  EXPECT_TRUE(cam->deltaPosition());

  // A mirror in to_world (Mitsuba scenes use scale x=-1) mirrors the image.
  CameraDesc m = lookingAlongZ(60, CameraDesc::FovAxis::X);
  m.toWorld = m.toWorld * Transform::scale({-1, 1, 1});
  auto mirrored = makeCamera(m)->rasterPosition({1, 0, 5});
  ASSERT_TRUE(mirrored);
  EXPECT_NEAR(mirrored->x, 64 - left->x, 1e-3f);
}

TEST(Camera, FovAxisSemantics) {
  using A = CameraDesc::FovAxis;
  auto halfAngle = [](const Camera& cam, Vec2 raster) {
    const Vec3 d = cam.generateRay(raster, {0.5f, 0.5f}).ray.d;
    return deg(std::acos(d.z));
  };
  // 64 x 48: x is the larger axis.
  EXPECT_NEAR(halfAngle(*makeCamera(lookingAlongZ(50, A::X)), {0, 24}), 25.0f, 1e-3f);
  EXPECT_NEAR(halfAngle(*makeCamera(lookingAlongZ(50, A::Y)), {32, 0}), 25.0f, 1e-3f);
  EXPECT_NEAR(halfAngle(*makeCamera(lookingAlongZ(50, A::Diagonal)), {0, 0}), 25.0f, 1e-3f);
  EXPECT_NEAR(halfAngle(*makeCamera(lookingAlongZ(50, A::Smaller)), {32, 0}), 25.0f, 1e-3f);
  EXPECT_NEAR(halfAngle(*makeCamera(lookingAlongZ(50, A::Larger)), {0, 24}), 25.0f, 1e-3f);
  // Portrait film: the smaller axis is x.
  EXPECT_NEAR(halfAngle(*makeCamera(lookingAlongZ(50, A::Smaller, 30, 60)), {0, 30}), 25.0f, 1e-3f);
}

// Directions of rays through uniform raster positions (at a fixed lens point) have solid-angle density
// pdfDir = 1 / (A cos^3).
// A 40x30 film with a 110-degree fov, looking along ~+x with z up; a thin lens (radius 0.2, focus 2.5) or
// a pinhole.
CameraDesc wideTiltedCamera(bool thinLens) {
  CameraDesc d = lookingAlongZ(110, CameraDesc::FovAxis::X, 40, 30);
  d.toWorld = Transform::lookAt({1, 2, 3}, {2, 2.3f, 3}, {0, 0, 1});
  if (thinLens) {
    d.type = CameraDesc::Type::ThinLens;
    d.apertureRadius = 0.2f;
    d.focusDistance = 2.5f;
  }
  return d;
}

TEST(Camera, GeneratedDirectionsMatchPdfDir) {
  for (bool thinLens : {false, true}) {
    const auto cam = makeCamera(wideTiltedCamera(thinLens));
    const Vec2 uLens(0.8f, 0.3f);
    const Vec3 o = cam->generateRay({1, 1}, uLens).ray.o;
    auto r = test::chi2TestSphere(
        [&](Pcg32& rng) -> std::optional<Vec3> {
          const Vec2 u = rng.uniform2();
          const CameraRay c = cam->generateRay({u.x * 40, u.y * 30}, uLens);
          EXPECT_NEAR(distance(c.ray.o, o), 0.0f, 1e-5f);
          return c.ray.d;
        },
        [&](const Vec3& w) {
          Ray ray;
          ray.o = o;
          ray.d = w;
          float pdfPos, pdfDir;
          cam->pdfWe(ray, &pdfPos, &pdfDir);
          return double(pdfDir);
        },
        20, 40, 200000, 0.01, kChi2Tests, thinLens ? 5 : 3);
    EXPECT_TRUE(r.passed) << (thinLens ? "thin lens: " : "pinhole: ") << r.message;
  }
}

// The densities generateRay returns with its ray (generateCameraSubpath's pdfFwd of the first vertex) are
// pdfWe's for that ray, to float rounding, over the whole film and the lens; and never zero, where pdfWe
// may round a ray from the film's very edge off the film (such a ray used to end its camera subpath).
TEST(Camera, GeneratedRayCarriesPdfWesDensities) {
  for (bool thinLens : {false, true}) {
    const auto cam = makeCamera(wideTiltedCamera(thinLens));
    Pcg32 rng(3, 4);
    for (int i = 0; i < 20000; ++i) {
      Vec2 u = rng.uniform2();
      if (i < 4) u = Vec2(i & 1 ? 0.999f : 0.0f, i & 2 ? 0.999f : 0.0f);  // the corners
      const CameraRay c = cam->generateRay({u.x * 40, u.y * 30}, rng.uniform2());
      float pdfPos = -1, pdfDir = -1;
      cam->pdfWe(c.ray, &pdfPos, &pdfDir);
      ASSERT_GT(c.pdfDir, 0) << "raster " << u.x * 40 << ", " << u.y * 30;
      if (pdfDir == 0) {  // pdfWe's projection back onto the film may round a ray from its very edge off it
        const float edge = std::fmin(std::fmin(u.x * 40, 40 - u.x * 40), std::fmin(u.y * 30, 30 - u.y * 30));
        ASSERT_LT(edge, 0.05f) << "raster " << u.x * 40 << ", " << u.y * 30;
        continue;
      }
      ASSERT_EQ(c.pdfPos, pdfPos);
      ASSERT_NEAR(c.pdfDir / pdfDir, 1.0, 2e-6) << "raster " << u.x * 40 << ", " << u.y * 30;
    }
  }
}

// int_lens int_dirs We cos dw dA = 1 (the film-normalized importance of pbrt-v3), by Monte Carlo with
// directions uniform in a cone that contains the frustum and, for the thin lens, uniform lens points.
TEST(Camera, ImportanceIntegratesToOne) {
  for (bool thinLens : {false, true}) {
    CameraDesc d = lookingAlongZ(50, CameraDesc::FovAxis::X, 64, 48);
    const float r = 0.3f;
    if (thinLens) {
      d.type = CameraDesc::Type::ThinLens;
      d.apertureRadius = r;
      d.focusDistance = 3;
    }
    const auto cam = makeCamera(d);
    const float tx = std::tan(25 * kPi / 180), ty = tx * 48 / 64;
    const float cosMax = 1 / std::sqrt(1 + tx * tx + ty * ty) - 0.01f;
    Pcg32 rng(9, thinLens);
    const int n = 400000;
    double sum = 0, sum2 = 0;
    int inside = 0;
    for (int i = 0; i < n; ++i) {
      Ray ray;
      double pdfPos = 1;
      if (thinLens) {
        const Vec2 p = sampleConcentricDisk(rng.uniform2()) * r;
        ray.o = Vec3(p.x, p.y, 0);  // the lens plane is the world xy plane here
        pdfPos = 1 / (kPi * r * r);
      }
      ray.d = sampleUniformCone(rng.uniform2(), cosMax);
      Vec2 pr;
      const double v = cam->We(ray, &pr).g * ray.d.z / (pdfPos * uniformConePdfW(cosMax));
      if (v > 0) {
        ++inside;
        EXPECT_TRUE(pr.x >= 0 && pr.x < 64 && pr.y >= 0 && pr.y < 48);
      }
      sum += v;
      sum2 += v * v;
    }
    const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, 1.0, 4 * se) << (thinLens ? "thin lens" : "pinhole") << ", standard error " << se;
    EXPECT_GT(inside, n / 4);
    EXPECT_LT(inside, n);  // the cone is wider than the frustum: some directions must get zero
  }
}

TEST(Camera, RoundTripThroughRasterPositionWeAndSampleWi) {
  for (bool thinLens : {false, true}) {
    CameraDesc d = lookingAlongZ(45, CameraDesc::FovAxis::Y, 80, 60);
    d.toWorld = Transform::lookAt({0.5f, 1, -4}, {0, 0.8f, 0}, {0, 1, 0});
    const float focus = 4.2f;
    if (thinLens) {
      d.type = CameraDesc::Type::ThinLens;
      d.apertureRadius = 0.1f;
      d.focusDistance = focus;
    }
    const auto cam = makeCamera(d);
    EXPECT_EQ(cam->deltaPosition(), !thinLens);
    Pcg32 rng(21, thinLens);
    for (int i = 0; i < 500; ++i) {
      const Vec2 p(rng.uniform() * 80, rng.uniform() * 60), uLens = rng.uniform2();
      const CameraRay c = cam->generateRay(p, uLens);
      ASSERT_NEAR(length(c.ray.d), 1.0f, 1e-5f);
      const float cosTheta = dot(c.ray.d, c.n);
      // A point on the ray: any depth for the pinhole, the plane in focus for the thin lens.
      const float depth = thinLens ? focus : 0.5f + 10 * rng.uniform();
      const Vec3 x = c.ray.at(depth / cosTheta);

      const auto pr = cam->rasterPosition(x);
      ASSERT_TRUE(pr);
      EXPECT_NEAR(pr->x, p.x, 2e-3f);
      EXPECT_NEAR(pr->y, p.y, 2e-3f);

      Vec2 pWe;
      const Color We = cam->We(c.ray, &pWe);
      EXPECT_NEAR(pWe.x, p.x, 2e-3f);
      EXPECT_NEAR(pWe.y, p.y, 2e-3f);
      float pdfPos, pdfDir;
      cam->pdfWe(c.ray, &pdfPos, &pdfDir);
      // We = pdfPos * pdfDir / cos (pbrt-v3: We = 1/(A lensArea cos^4), pdfDir = 1/(A cos^3)).
      EXPECT_NEAR(We.r, pdfPos * pdfDir / cosTheta, 1e-4f * We.r);

      const auto s = cam->sampleWi(x, rng.uniform2());
      ASSERT_TRUE(s);
      EXPECT_NEAR(s->pRaster.x, p.x, 2e-3f);
      EXPECT_NEAR(s->pRaster.y, p.y, 2e-3f);
      EXPECT_NEAR(dot(s->wi, normalize(s->pLens - x)), 1.0f, 1e-5f);
      const float d2 = distanceSquared(x, s->pLens), cosLens = absDot(s->wi, s->nLens);
      Ray back;
      back.o = s->pLens;
      back.d = -s->wi;
      EXPECT_NEAR(s->We.g, cam->We(back, nullptr).g, 1e-4f * s->We.g);
      cam->pdfWe(back, &pdfPos, &pdfDir);
      EXPECT_NEAR(s->pdfW, d2 / cosLens * pdfPos, 1e-3f * s->pdfW);  // pdfA (1/lensArea) -> solid angle
      if (!thinLens) {
        EXPECT_NEAR(distance(s->pLens, c.ray.o), 0.0f, 1e-5f);
        EXPECT_NEAR(s->We.g, We.g, 1e-4f * We.g);
      }
    }
  }
}

TEST(Camera, NearClipAndPointsOffTheFilm) {
  CameraDesc d = lookingAlongZ(60, CameraDesc::FovAxis::X);
  d.nearClip = 0.5f;
  const auto cam = makeCamera(d);
  const CameraRay c = cam->generateRay({5, 7}, {0.5f, 0.5f});
  EXPECT_NEAR(c.ray.at(c.ray.tMin).z, 0.5f, 1e-5f);  // starts on the near plane
  EXPECT_FALSE(cam->rasterPosition({0, 0, 0.4f}));
  EXPECT_FALSE(cam->sampleWi({0, 0, 0.4f}, {0.5f, 0.5f}));
  EXPECT_TRUE(cam->rasterPosition({0, 0, 0.6f}));
  EXPECT_FALSE(cam->rasterPosition({0, 0, -3}));  // behind
  EXPECT_FALSE(cam->rasterPosition({10, 0, 3}));  // outside the fov
  EXPECT_FALSE(cam->sampleWi({10, 0, 3}, {0.5f, 0.5f}));
  Ray behind;
  behind.d = {0, 0, -1};
  EXPECT_TRUE(cam->We(behind, nullptr).isBlack());
  float pdfPos = 1, pdfDir = 1;
  cam->pdfWe(behind, &pdfPos, &pdfDir);
  EXPECT_EQ(pdfDir, 0.0f);
}

TEST(Camera, RejectsBadDescriptions) {
  CameraDesc d = lookingAlongZ(60, CameraDesc::FovAxis::X);
  d.width = 0;
  EXPECT_THROW(makeCamera(d), std::runtime_error);
  d = lookingAlongZ(0, CameraDesc::FovAxis::X);
  EXPECT_THROW(makeCamera(d), std::runtime_error);
  d = lookingAlongZ(60, CameraDesc::FovAxis::X);
  d.toWorld = d.toWorld * Transform::scale({1, 2, 1});
  EXPECT_THROW(makeCamera(d), std::runtime_error);
  d = lookingAlongZ(60, CameraDesc::FovAxis::X);
  d.type = CameraDesc::Type::ThinLens;
  d.apertureRadius = 0.1f;
  d.focusDistance = 0;
  EXPECT_THROW(makeCamera(d), std::runtime_error);
}

}  // namespace
}  // namespace mlt
