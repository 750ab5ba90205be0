// Lights: chi-square tests of every sampling routine against the pdf the light reports (sampleLi vs
// pdfLi as a solid-angle density from several reference points, sampleLe directions vs pdfDir, positions
// on area lights and emission disks), pdf consistency, emitted power (MC integral of sampleLe) and the
// spot light's falloff; the light sampler's choice probabilities.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/core/sampling.h"
#include "common/emitter/light_factories.h"
#include "common/emitter/light_sampler.h"
#include "common/emitter/make_light.h"
#include "common/interfaces/light.h"
#include "common/scene/mesh_utils.h"
#include "common/scene/scene_desc.h"
#include "tests/support/chi2.h"
#include "tests/support/mesh_density.h"

namespace mlt {
namespace {

using test::chi2Test2D;
using test::chi2TestSphere;
using test::meshPdfW;

constexpr int kChi2Tests = 17;  // Sidak correction across the chi-square tests of this file

// An emitting octahedron with unequal triangle areas (stretched along x), centered at c.
MeshDesc octahedron(const Vec3& c, const Vec3& scale, Color Le) {
  MeshDesc m;
  m.name = "octahedron";
  const Vec3 v[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Vec3& p : v) m.positions.push_back(c + mul(p, scale));
  // Faces wound counter-clockwise seen from outside (normals point out).
  const uint32_t f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (auto& t : f) m.indices.insert(m.indices.end(), {t[0], t[1], t[2]});
  m.emission = Le;
  m.bsdf = 0;
  return m;
}

// A planar trapezoid in the plane z = 0 (two triangles of different areas), facing +z.
MeshDesc trapezoid(Color Le) {
  MeshDesc m;
  m.name = "trapezoid";
  m.positions = {{0, 0, 0}, {4, 0, 0}, {3, 2, 0}, {0, 2, 0}};
  m.indices = {0, 1, 2, 0, 2, 3};
  m.emission = Le;
  m.bsdf = 0;
  return m;
}
bool insideTrapezoid(Vec2 p) { return p.x >= 0 && p.y >= 0 && p.y <= 2 && p.x <= 4 - 0.5f * p.y; }

// ---- area light -----------------------------------------------------------------------------------
TEST(AreaLight, SampleLiMatchesPdfLiFromSeveralPoints) {
  const MeshDesc mesh = octahedron({0, 0, 2}, {1.5f, 0.8f, 1.0f}, Color(1, 2, 3));
  const auto light = makeAreaLight(mesh);
  // Outside (two hits per direction), near a vertex, and inside (one hit in every direction).
  for (const Vec3 ref : {Vec3(0.3f, -0.2f, 0.0f), Vec3(2.2f, 0.5f, 2.3f), Vec3(0.1f, 0.05f, 2.1f)}) {
    auto r = chi2TestSphere(
        [&](Pcg32& rng) -> std::optional<Vec3> {
          auto s = light->sampleLi(ref, rng.uniform2());
          if (!s) return std::nullopt;
          return s->wi;
        },
        [&](const Vec3& w) { return meshPdfW(*light, mesh, ref, w); }, 20, 40, 100000, 0.01, kChi2Tests, 7);
    EXPECT_TRUE(r.passed) << "ref (" << ref.x << "," << ref.y << "," << ref.z << "): " << r.message;
  }
}

TEST(AreaLight, SampleLiFieldsConsistent) {
  const MeshDesc mesh = octahedron({0, 0, 2}, {1.5f, 0.8f, 1.0f}, Color(1, 2, 3));
  const auto light = makeAreaLight(mesh);
  const Vec3 ref(0.3f, -0.2f, 0.0f);
  Pcg32 rng(3, 4);
  int front = 0, back = 0;
  for (int i = 0; i < 2000; ++i) {
    auto s = light->sampleLi(ref, rng.uniform2());
    ASSERT_TRUE(s);
    EXPECT_NEAR(length(s->wi), 1.0f, 1e-5f);
    EXPECT_NEAR(dot(normalize(s->pLight - ref), s->wi), 1.0f, 1e-5f);
    EXPECT_NEAR(s->pdfW, light->pdfLi(ref, s->pLight, s->nLight, s->wi), 1e-4f * s->pdfW);
    EXPECT_NEAR(s->pdfA * distanceSquared(ref, s->pLight) / absDot(s->nLight, s->wi), s->pdfW, 1e-3f * s->pdfW);
    EXPECT_FALSE(s->deltaPosition);
    EXPECT_FALSE(s->infinite);
    // Emission on the front side only: L equals the light's L(p, n, uv, -wi).
    const Color L = light->L(s->pLight, s->nLight, {}, -s->wi);
    EXPECT_EQ(s->L.g, L.g);
    (dot(s->nLight, -s->wi) > 0 ? front : back)++;
  }
  EXPECT_GT(front, 0);
  EXPECT_GT(back, 0);
  EXPECT_EQ(light->L({}, Vec3(0, 0, 1), {}, Vec3(0, 0.1f, 1)).b, 3.0f);
  EXPECT_EQ(light->L({}, Vec3(0, 0, 1), {}, Vec3(0, 0.1f, -1)).b, 0.0f);
}

TEST(AreaLight, PositionsUniformByArea) {
  const MeshDesc mesh = trapezoid(Color(1));
  const auto light = makeAreaLight(mesh);
  const double area = 7.0;  // (4 + 3) / 2 * 2
  auto r = chi2Test2D(
      [&](Pcg32& rng) -> std::optional<Vec2> {
        const Vec2 uPos = rng.uniform2(), uDir = rng.uniform2();
        auto s = light->sampleLe(uPos, uDir);
        if (!s) return std::nullopt;
        if (std::fabs(s->ray.o.z) > 1e-6f) return Vec2(-100, -100);  // off the plane: fails the test
        EXPECT_NEAR(s->pdfPos, 1 / area, 1e-6);
        return Vec2(s->ray.o.x, s->ray.o.y);
      },
      [&](Vec2 p) { return insideTrapezoid(p) ? 1 / area : 0.0; }, {0, 0}, {4, 2}, 16, 8, 100000, 0.01, kChi2Tests, 11);
  EXPECT_TRUE(r.passed) << r.message;
}

// A light of more than 16 triangles picks its triangle in two levels (area_light.cpp): still uniform by
// area. The rectangle [0,4] x [0,2] in the plane z = 0 as 20 x 5 cells of unequal widths (x_i = 4 (i/20)^2),
// two triangles each.
TEST(AreaLight, PositionsUniformByAreaWithManyTriangles) {
  MeshDesc m;
  m.name = "grid";
  const int nx = 20, ny = 5;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.positions.push_back({4.0f * float(i * i) / (nx * nx), 2.0f * j / ny, 0});
  const auto at = [&](int i, int j) { return uint32_t(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.indices.insert(m.indices.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
  m.emission = Color(1);
  m.bsdf = 0;
  const auto light = makeAreaLight(m);
  auto r = chi2Test2D(
      [&](Pcg32& rng) -> std::optional<Vec2> {
        auto s = light->sampleLe(rng.uniform2(), rng.uniform2());
        if (!s) return std::nullopt;
        if (std::fabs(s->ray.o.z) > 1e-6f) return Vec2(-100, -100);
        EXPECT_NEAR(s->pdfPos, 1 / 8.0, 1e-6);
        return Vec2(s->ray.o.x, s->ray.o.y);
      },
      [&](Vec2) { return 1 / 8.0; }, {0, 0}, {4, 2}, 16, 8, 100000, 0.01, kChi2Tests, 12);
  EXPECT_TRUE(r.passed) << r.message;
}

// Markov chains need a small step of the position numbers to be a small move of the light point: on a
// tessellated sphere (16256 facets, the bundled scenes' sphere lights) a step of 1/1024, the Kelemen
// kernel's smallest, must mostly stay on the same facet (same normal, which the emitted direction is
// sampled around). With the triangle picked by u.x alone every facet owned ~6e-5 of u.x and such a step
// never stayed (the stuck chains of glossy-plates, tests/mlt_stuck_test.cpp).
TEST(AreaLight, SmallPositionStepsStayOnTheFacet) {
  MeshDesc m = makeSphere();
  m.name = "sphere";
  m.emission = Color(1);
  m.bsdf = 0;
  const auto light = makeAreaLight(m);
  Pcg32 rng(5, 6);
  const int n = 4000;
  int same[2] = {0, 0};
  for (int i = 0; i < n; ++i) {
    const Vec2 u = rng.uniform2(), dir = rng.uniform2();
    const auto s0 = light->sampleLe(u, dir);
    ASSERT_TRUE(s0);
    for (int axis = 0; axis < 2; ++axis) {
      Vec2 v = u;
      (axis == 0 ? v.x : v.y) = std::fmod((axis == 0 ? u.x : u.y) + 1.0f / 1024, 1.0f);
      const auto s1 = light->sampleLe(v, dir);
      ASSERT_TRUE(s1);
      if (s1->nLight.x == s0->nLight.x && s1->nLight.y == s0->nLight.y && s1->nLight.z == s0->nLight.z) ++same[axis];
    }
  }
  EXPECT_GT(same[0], 0.7 * n) << "u.x steps of 1/1024 leave the facet";
  EXPECT_GT(same[1], 0.7 * n) << "u.y steps of 1/1024 leave the facet";
}

TEST(AreaLight, SampleLeDirectionsMatchPdfDir) {
  const MeshDesc mesh = octahedron({0, 0, 2}, {1.5f, 0.8f, 1.0f}, Color(1));
  const auto light = makeAreaLight(mesh);
  for (const Vec2 uPos : {Vec2(0.1f, 0.3f), Vec2(0.77f, 0.9f)}) {
    const auto s0 = light->sampleLe(uPos, {0.5f, 0.5f});
    ASSERT_TRUE(s0);
    auto r = chi2TestSphere(
        [&](Pcg32& rng) -> std::optional<Vec3> {
          auto s = light->sampleLe(uPos, rng.uniform2());
          if (!s) return std::nullopt;
          return s->ray.d;
        },
        [&](const Vec3& w) {
          float pdfPos, pdfDir;
          light->pdfLe(s0->ray.o, s0->nLight, w, &pdfPos, &pdfDir);
          return double(pdfDir);
        },
        20, 40, 100000, 0.01, kChi2Tests, 13);
    EXPECT_TRUE(r.passed) << r.message;
  }
}

TEST(AreaLight, RejectsMeshesWithoutAreaOrEmission) {
  MeshDesc m = trapezoid(Color(1));
  m.emission.reset();
  EXPECT_THROW(makeAreaLight(m), std::runtime_error);
  MeshDesc flat = trapezoid(Color(1));
  for (Vec3& p : flat.positions) p.y = 0;  // all triangles degenerate
  EXPECT_THROW(makeAreaLight(flat), std::runtime_error);
}

// ---- emitted power: E[L |cos| / (pdfPos pdfDir)] over sampleLe equals power() ----------------------
void expectPowerMatches(const Light& light, int n, uint64_t seed) {
  Pcg32 rng(seed, 1);
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const Vec2 uPos = rng.uniform2(), uDir = rng.uniform2();
    auto s = light.sampleLe(uPos, uDir);
    double v = 0;
    if (s && s->pdfPos > 0 && s->pdfDir > 0) {
      const bool noNormal = s->nLight.x == 0 && s->nLight.y == 0 && s->nLight.z == 0;
      const double cosL = noNormal ? 1.0 : absDot(s->nLight, s->ray.d);
      v = luminance(s->L) * cosL / (double(s->pdfPos) * s->pdfDir);
    }
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
  const double expected = luminance(light.power());
  EXPECT_NEAR(mean, expected, 4 * se + 1e-4 * expected) << "standard error " << se;
}

TEST(LightPower, MonteCarloIntegralOfEmissionEqualsPower) {
  const Vec3 c(1, 2, 3);
  const float R = 2.5f;
  auto area = makeAreaLight(octahedron({0, 0, 2}, {1.5f, 0.8f, 1.0f}, Color(1, 2, 3)));
  auto point = makePointLight({1, 1, 1}, Color(2, 1, 0.5f));
  auto spot = makeSpotLight({0, 0, 0}, {0, 1, 1}, Color(3), 30, 10);
  auto spotHard = makeSpotLight({0, 0, 0}, {1, 0, 0}, Color(3), 25, 25);
  auto spotSoft = makeSpotLight({0, 0, 0}, {1, 0, 0}, Color(3), 60, 0);
  auto spotPbrt = makeSpotLight({0, 0, 0}, {0, 1, 0}, Color(3), 30, 25, SpotFalloffCurve::PbrtQuartic);
  auto spotPbrtSoft = makeSpotLight({0, 0, 0}, {0, 0, 1}, Color(3), 40, 0, SpotFalloffCurve::PbrtQuartic);
  auto dir = makeDirectionalLight({0, 0, -1}, Color(1.5f));
  auto env = makeConstantEnvironment(Color(0.5f, 1, 2));
  dir->preprocess(c, R);
  env->preprocess(c, R);
  uint64_t seed = 100;
  for (const Light* l : {area.get(), point.get(), spot.get(), spotHard.get(), spotSoft.get(), spotPbrt.get(),
                         spotPbrtSoft.get(), dir.get(), env.get()})
    expectPowerMatches(*l, 200000, seed++);
  // Closed forms.
  EXPECT_NEAR(luminance(point->power()), 4 * kPi * luminance(Color(2, 1, 0.5f)), 1e-4);
  EXPECT_NEAR(dir->power().r, 1.5f * kPi * R * R, 1e-3);
  EXPECT_NEAR(spotHard->power().r, 3 * 2 * kPi * (1 - std::cos(25 * kPi / 180)), 1e-3);
}

// ---- point light ----------------------------------------------------------------------------------
TEST(PointLight, InverseSquareAndDeltaConventions) {
  const Vec3 p(1, -2, 3);
  auto light = makePointLight(p, Color(2, 4, 8));
  EXPECT_TRUE(light->deltaPosition());
  EXPECT_FALSE(light->infinite());
  for (const Vec3 ref : {Vec3(0, 0, 0), Vec3(4, 1, -1), Vec3(1, -2, 3.5f)}) {
    auto s = light->sampleLi(ref, {0.3f, 0.7f});
    ASSERT_TRUE(s);
    const float d2 = distanceSquared(ref, p);
    EXPECT_NEAR(s->L.g, 4 / d2, 1e-5f * 4 / d2);
    EXPECT_NEAR(dot(s->wi, normalize(p - ref)), 1.0f, 1e-6f);
    EXPECT_EQ(s->pdfW, 1.0f);
    EXPECT_TRUE(s->deltaPosition);
    EXPECT_EQ(light->pdfLi(ref, p, {}, s->wi), 0.0f);
  }
}

TEST(PointLight, SampleLeDirectionsUniform) {
  auto light = makePointLight({0, 0, 0}, Color(1));
  auto r = chi2TestSphere(
      [&](Pcg32& rng) -> std::optional<Vec3> { return light->sampleLe(rng.uniform2(), rng.uniform2())->ray.d; },
      [&](const Vec3& w) {
        float pp, pd;
        light->pdfLe({}, {}, w, &pp, &pd);
        return double(pd);
      },
      20, 40, 100000, 0.01, kChi2Tests, 17);
  EXPECT_TRUE(r.passed) << r.message;
}

// ---- spot light -----------------------------------------------------------------------------------
TEST(SpotLight, FalloffMonotoneAndZeroBeyondCutoff) {
  const float cutoff = 30, beam = 12;
  auto light = makeSpotLight({0, 0, 0}, {0, 0, 1}, Color(5), cutoff, beam);
  float prev = 1e30f;
  for (int i = 0; i <= 400; ++i) {
    const float theta = i * 0.25f * kPi / 180;  // 0 .. 100 degrees
    const Vec3 ref(std::sin(theta), 0, std::cos(theta));  // at distance 1
    const float I = light->sampleLi(ref, {0, 0})->L.r;
    const float deg = theta * 180 / kPi;
    EXPECT_LE(I, prev + 1e-6f) << deg;
    if (deg < beam - 0.01f) {
      EXPECT_NEAR(I, 5.0f, 1e-4f) << deg;
    }
    if (deg > beam + 0.01f && deg < cutoff - 0.01f) {
      EXPECT_LT(I, 5.0f) << deg;
      EXPECT_GT(I, 0.0f) << deg;
      EXPECT_NEAR(I, 5 * (cutoff - deg) / (cutoff - beam), 1e-2f) << deg;  // Mitsuba: linear in angle
    }
    if (deg >= cutoff) {
      EXPECT_EQ(I, 0.0f) << deg;
    }
    prev = I;
  }
}

// pbrt-v3's SpotLight::Falloff (coneangle 30, conedelta 5): 1 inside 25 degrees, delta^4 with delta linear in
// cos theta between cos 30 and cos 25, 0 beyond 30 degrees.
TEST(SpotLight, PbrtQuarticFalloff) {
  const float cone = 30, beam = 25;
  auto light = makeSpotLight({0, 0, 0}, {0, 0, 1}, Color(5), cone, beam, SpotFalloffCurve::PbrtQuartic);
  const double cosTotal = std::cos(cone * kPi / 180), cosStart = std::cos(beam * kPi / 180);
  for (double deg : {0.0, 10.0, 24.9, 25.5, 27.0, 28.5, 29.9, 30.1, 45.0}) {
    const double theta = deg * kPi / 180;
    const Vec3 ref(float(std::sin(theta)), 0, float(std::cos(theta)));
    const float I = light->sampleLi(ref, {0, 0})->L.r;
    double expected = 5;
    if (deg >= cone) expected = 0;
    else if (deg > beam) expected = 5 * std::pow((std::cos(theta) - cosTotal) / (cosStart - cosTotal), 4);
    EXPECT_NEAR(I, expected, 2e-3 * 5) << deg;
  }
}

TEST(SpotLight, SampleLeDirectionsMatchPdfDir) {
  auto light = makeSpotLight({1, 1, 1}, {1, 1, 0}, Color(1), 50, 20);
  auto r = chi2TestSphere(
      [&](Pcg32& rng) -> std::optional<Vec3> { return light->sampleLe(rng.uniform2(), rng.uniform2())->ray.d; },
      [&](const Vec3& w) {
        float pp, pd;
        light->pdfLe({1, 1, 1}, {}, w, &pp, &pd);
        return double(pd);
      },
      20, 40, 100000, 0.01, kChi2Tests, 19);
  EXPECT_TRUE(r.passed) << r.message;
}

// ---- directional light ----------------------------------------------------------------------------
TEST(DirectionalLight, SampleLiAndEmissionDisk) {
  const Vec3 d = normalize(Vec3(1, -2, -1)), c(0.5f, 1, -1);
  const float R = 3;
  auto light = makeDirectionalLight(d, Color(2));
  light->preprocess(c, R);
  EXPECT_TRUE(light->deltaDirection());
  EXPECT_TRUE(light->infinite());
  auto s = light->sampleLi({1, 1, 1}, {0.2f, 0.2f});
  ASSERT_TRUE(s);
  EXPECT_NEAR(dot(s->wi, -d), 1.0f, 1e-6f);
  EXPECT_EQ(s->L.r, 2.0f);
  EXPECT_TRUE(s->infinite);
  EXPECT_GE(distance(s->pLight, Vec3(1, 1, 1)), 2 * R - 1e-3f);

  const Frame f(d);
  auto r = chi2Test2D(
      [&](Pcg32& rng) -> std::optional<Vec2> {
        auto le = light->sampleLe(rng.uniform2(), rng.uniform2());
        EXPECT_NEAR(dot(le->ray.d, d), 1.0f, 1e-6f);
        EXPECT_NEAR(dot(le->ray.o - c, d), -R, 1e-4f);  // the disk sits R behind the center
        EXPECT_NEAR(le->pdfPos, 1 / (kPi * R * R), 1e-6f);
        const Vec3 q = le->ray.o - c;
        return Vec2(dot(q, f.s), dot(q, f.t));
      },
      [&](Vec2 p) { return p.x * p.x + p.y * p.y <= R * R ? 1 / (kPi * R * R) : 0.0; }, {-R, -R}, {R, R}, 16, 16,
      100000, 0.01, kChi2Tests, 23);
  EXPECT_TRUE(r.passed) << r.message;
}

// ---- constant environment -------------------------------------------------------------------------
TEST(ConstantEnvironment, SampleLiMatchesPdfLi) {
  auto light = makeConstantEnvironment(Color(0.7f));
  light->preprocess({0, 0, 0}, 2);
  const Vec3 ref(0.5f, 0.2f, -0.3f);
  auto r = chi2TestSphere(
      [&](Pcg32& rng) -> std::optional<Vec3> {
        auto s = light->sampleLi(ref, rng.uniform2());
        EXPECT_NEAR(dot(s->nLight, -s->wi), 1.0f, 1e-6f);
        EXPECT_EQ(s->L.r, light->Le(s->wi).r);
        return s->wi;
      },
      [&](const Vec3& w) { return double(light->pdfLi(ref, ref + w * 4.0f, -w, w)); }, 20, 40, 100000, 0.01,
      kChi2Tests, 29);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(ConstantEnvironment, SampleLeDirectionsAndDisk) {
  auto light = makeConstantEnvironment(Color(0.7f));
  const Vec3 c(1, 0, 0);
  const float R = 2;
  light->preprocess(c, R);
  auto r = chi2TestSphere(
      [&](Pcg32& rng) -> std::optional<Vec3> { return light->sampleLe(rng.uniform2(), rng.uniform2())->ray.d; },
      [&](const Vec3& w) {
        float pp, pd;
        light->pdfLe({}, {}, w, &pp, &pd);
        return double(pd);
      },
      20, 40, 100000, 0.01, kChi2Tests, 31);
  EXPECT_TRUE(r.passed) << r.message;
  // Origins: uniform on the disk of radius R perpendicular to the direction, R behind the center.
  auto r2 = chi2Test2D(
      [&](Pcg32& rng) -> std::optional<Vec2> {
        auto le = light->sampleLe(rng.uniform2(), rng.uniform2());
        const Frame f(le->ray.d);
        const Vec3 q = le->ray.o - c;
        EXPECT_NEAR(dot(q, le->ray.d), -R, 1e-4f);
        return Vec2(dot(q, f.s), dot(q, f.t));
      },
      [&](Vec2 p) { return p.x * p.x + p.y * p.y <= R * R ? 1 / (kPi * R * R) : 0.0; }, {-R, -R}, {R, R}, 16, 16,
      100000, 0.01, kChi2Tests, 37);
  EXPECT_TRUE(r2.passed) << r2.message;
}

// ---- factory and light selection ------------------------------------------------------------------
TEST(MakeLight, DispatchesAndValidates) {
  LightDesc d;
  d.type = LightDesc::Type::Spot;
  d.direction = {0, 0, 2};
  EXPECT_TRUE(makeLight(d)->deltaPosition());
  d.beamWidthDeg = d.cutoffAngleDeg + 1;
  EXPECT_THROW(makeLight(d), std::runtime_error);
  d.type = LightDesc::Type::Constant;
  EXPECT_TRUE(makeLight(d)->infinite());
  d.type = LightDesc::Type::Directional;
  EXPECT_TRUE(makeLight(d)->deltaDirection());
  d.direction = {0, 0, 0};
  EXPECT_THROW(makeLight(d), std::runtime_error);
  d.direction = {0, 0, 1};
  d.intensity = Color(-1);
  EXPECT_THROW(makeLight(d), std::runtime_error);
  d.intensity = Color(std::nanf(""));
  EXPECT_THROW(makeLight(d), std::runtime_error);
}

TEST(LightSampler, ChoosesInProportionToPower) {
  auto a = makePointLight({}, Color(1));        // luminance of power 4 pi
  auto b = makePointLight({}, Color(0));        // never chosen
  auto c = makePointLight({}, Color(0, 3, 0));  // 0.71516 * 3 * 4 pi
  LightSampler sampler({a.get(), b.get(), c.get()});
  const double wa = 1, wc = 0.715160 * 3;
  EXPECT_NEAR(sampler.pmf(0), wa / (wa + wc), 1e-5);
  EXPECT_EQ(sampler.pmf(1), 0.0f);
  EXPECT_NEAR(sampler.pmf(2), wc / (wa + wc), 1e-5);
  EXPECT_EQ(sampler.pmf(3), 0.0f);
  Pcg32 rng(5, 5);
  const int n = 100000;
  int count[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    float pmf;
    const int k = sampler.sample(rng.uniform(), &pmf);
    ASSERT_GE(k, 0);
    EXPECT_EQ(pmf, sampler.pmf(k));
    count[k]++;
  }
  EXPECT_EQ(count[1], 0);
  const double p0 = sampler.pmf(0);
  EXPECT_NEAR(count[0], n * p0, 4 * std::sqrt(n * p0 * (1 - p0)));
  float pmf = 1;
  EXPECT_EQ(sampler.sample(kOneMinusEpsilon, &pmf), 2);
  EXPECT_EQ(LightSampler({}).sample(0.5f, &pmf), -1);
  EXPECT_EQ(pmf, 0.0f);
}

}  // namespace
}  // namespace mlt
