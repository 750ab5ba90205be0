// Inverses of light selection and of every emitter's sampleLi / sampleLe (reversible-jump MLT, Bitterli
// et al. 2017, sec. 5-6): round trip sample -> invert -> sample lands on the same point / ray to 1e-4
// relative, the Jacobians equal the densities the forward routines report, and the inverted numbers of
// uniform numbers are uniform (two-sample chi-square; the light choice's ambiguous interval (eq. 40) and
// the unread coordinates of delta lights included). Area lights are tested on meshes with unequal
// triangles, so the triangle choice through the CDF is part of the inverse. Fixed seeds.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "common/core/rng.h"
#include "common/core/sampling.h"
#include "common/emitter/light_factories.h"
#include "common/emitter/light_sampler.h"
#include "common/emitter/make_light.h"
#include "common/scene/scene_desc.h"
#include "tests/support/two_sample_chi2.h"

namespace mlt {
namespace {

constexpr int kUniformityTests = 8;

MeshDesc octahedron(const Vec3& c, const Vec3& scale) {
  MeshDesc m;
  m.name = "octahedron";
  const Vec3 v[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Vec3& p : v) m.positions.push_back(c + mul(p, scale));
  const uint32_t f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (auto& t : f) m.indices.insert(m.indices.end(), {t[0], t[1], t[2]});
  m.emission = Color(2.0f);
  return m;
}

// A bumpy grid of n x n quads (2 n^2 triangles of varying area and orientation) facing roughly -y.
MeshDesc bumpyGrid(int n) {
  MeshDesc m;
  m.name = "grid";
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = float(i) / n + 0.3f * float(j % 3) / n, z = float(j) / n * (1 + 0.5f * float(i) / n);
      m.positions.push_back({x, 2.0f + 0.2f * std::sin(7.0f * x + 3.0f * z), z});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + (n + 1), d = c + 1;
      m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
    }
  m.emission = Color(1.0f);
  return m;
}

struct NamedLight {
  std::string name;
  std::unique_ptr<Light> light;
  float scale;  // size of the positions involved, for relative tolerances
};

std::vector<NamedLight> everyLight() {
  std::vector<NamedLight> v;
  v.push_back({"area_octahedron", makeAreaLight(octahedron({0.5f, 1, -0.3f}, {2.0f, 0.5f, 0.8f})), 3});
  v.push_back({"area_grid_800", makeAreaLight(bumpyGrid(20)), 3});
  v.push_back({"point", makePointLight({0.2f, 3, 1}, Color(5.0f)), 3});
  v.push_back({"spot", makeSpotLight({0, 3, 0}, {0.2f, -1, 0.1f}, Color(5.0f), 30, 20), 3});
  v.push_back({"directional", makeDirectionalLight({0.3f, -1, 0.2f}, Color(2.0f)), 20});
  v.push_back({"constant_environment", makeConstantEnvironment(Color(0.5f)), 20});
  for (NamedLight& l : v) l.light->preprocess({0, 0, 0}, 10);
  return v;
}

InverseGamma randomGamma(Pcg32& rng) {
  InverseGamma g;
  g.pick = rng.uniform();
  g.fill = rng.uniform2();
  return g;
}
bool inUnit(Vec2 u) { return u.x >= 0 && u.x < 1 && u.y >= 0 && u.y < 1; }
bool relClose(float a, float b, float tol = 1e-4f) { return std::fabs(a - b) <= tol * std::fmax(std::fabs(a), std::fabs(b)); }

TEST(InverseLight, SampleLiRoundTripAndJacobian) {
  constexpr int kSamples = 20000;
  for (const NamedLight& nl : everyLight()) {
    SCOPED_TRACE(nl.name);
    Pcg32 rng(21, 1);
    int forward = 0, bad = 0;
    for (int i = 0; i < kSamples; ++i) {
      const Vec3 ref = Vec3(rng.uniform() - 0.5f, rng.uniform() - 1.0f, rng.uniform() - 0.5f) * 2.0f;
      const std::optional<LightLiSample> s = nl.light->sampleLi(ref, rng.uniform2());
      const InverseGamma gamma = randomGamma(rng);
      if (!s) continue;
      ++forward;
      const std::optional<Inverse2D> inv = nl.light->invertSampleLi(ref, s->pLight, s->nLight, gamma);
      bool ok = false;
      float dp = -1;
      if (inv && inUnit(inv->u)) {
        if (const std::optional<LightLiSample> s2 = nl.light->sampleLi(ref, inv->u)) {
          dp = length(s2->pLight - s->pLight);
          ok = dp <= 1e-4f * nl.scale && relClose(inv->jacobian, s->infinite ? s->pdfW : s->pdfA);
        }
      }
      if (!ok && bad++ < 3)
        ADD_FAILURE() << "sample " << i << (inv ? "" : " rejected") << " |dp| = " << dp
                      << (inv ? " J = " + std::to_string(inv->jacobian) : std::string()) << " pdfA = " << s->pdfA;
    }
    EXPECT_GT(forward, kSamples / 2);
  }
}

TEST(InverseLight, SampleLeRoundTripAndJacobian) {
  constexpr int kSamples = 20000;
  for (const NamedLight& nl : everyLight()) {
    SCOPED_TRACE(nl.name);
    Pcg32 rng(22, 1);
    int forward = 0, bad = 0;
    for (int i = 0; i < kSamples; ++i) {
      const Vec2 uPos = rng.uniform2(), uDir = rng.uniform2();
      const std::optional<LightLeSample> s = nl.light->sampleLe(uPos, uDir);
      const InverseGamma gamma = randomGamma(rng);
      if (!s) continue;
      ++forward;
      const std::optional<LightLeInverse> inv = nl.light->invertSampleLe(s->ray.o, s->nLight, s->ray.d, gamma);
      bool ok = false;
      float dOrigin = -1, dDir = -1;
      if (inv && inUnit(inv->pos.u) && inUnit(inv->dir.u)) {
        if (const std::optional<LightLeSample> s2 = nl.light->sampleLe(inv->pos.u, inv->dir.u)) {
          dOrigin = length(s2->ray.o - s->ray.o);
          dDir = length(s2->ray.d - s->ray.d);
          ok = dOrigin <= 1e-4f * nl.scale && dDir <= 1e-4f && relClose(inv->pos.jacobian, s->pdfPos) &&
               relClose(inv->dir.jacobian, s->pdfDir);
        }
      }
      if (!ok && bad++ < 3)
        ADD_FAILURE() << "sample " << i << (inv ? "" : " rejected") << " |do| = " << dOrigin << " |dd| = " << dDir;
    }
    EXPECT_GT(forward, kSamples / 2);
  }
}

// Points off the light, and rays the light cannot emit, are rejected.
TEST(InverseLight, RejectsWhatCannotBeSampled) {
  const std::vector<NamedLight> lights = everyLight();
  const InverseGamma g;
  EXPECT_FALSE(lights[0].light->invertSampleLi({0, 0, 0}, {7, 7, 7}, {0, 1, 0}, g));  // off the octahedron
  EXPECT_FALSE(lights[2].light->invertSampleLe({0, 0, 0}, {}, {0, 1, 0}, g));         // not the point light
  EXPECT_FALSE(lights[3].light->invertSampleLe({0, 3, 0}, {}, {0, 1, 0}, g));         // outside the spot cone
  EXPECT_FALSE(lights[4].light->invertSampleLe({0, 0, 0}, {}, {0, 1, 0}, g));         // not the direction
}

// Inverted numbers of uniform numbers are uniform on the success region (4D: uPos, uDir).
TEST(InverseLight, InverseOfUniformIsUniform) {
  for (const NamedLight& nl : everyLight()) {
    SCOPED_TRACE(nl.name);
    Pcg32 ra(31, 1), rb(31, 2);
    std::vector<float> a, b;
    constexpr int n = 120000;
    for (int i = 0; i < n; ++i) {
      const Vec2 uPos = ra.uniform2(), uDir = ra.uniform2();
      if (nl.light->sampleLe(uPos, uDir)) a.insert(a.end(), {uPos.x, uPos.y, uDir.x, uDir.y});
    }
    for (int i = 0; i < n; ++i) {
      const Vec2 uPos = rb.uniform2(), uDir = rb.uniform2();
      const std::optional<LightLeSample> s = nl.light->sampleLe(uPos, uDir);
      const InverseGamma gamma = randomGamma(rb);
      if (!s) continue;
      if (auto inv = nl.light->invertSampleLe(s->ray.o, s->nLight, s->ray.d, gamma))
        b.insert(b.end(), {inv->pos.u.x, inv->pos.u.y, inv->dir.u.x, inv->dir.u.y});
    }
    const test::TwoSampleResult r = test::twoSampleChi2(a, b, 4, 5, 0.01, kUniformityTests);
    EXPECT_TRUE(r.passed) << r.message;
  }
}

// Light selection by power: the inverse lands in the chosen light's interval (Jacobian = pmf), is
// uniform there (eq. 40), and the inverse of a fixed gamma is detected as non-uniform.
TEST(InverseLightSampler, IntervalJacobianAndUniformity) {
  std::vector<std::unique_ptr<Light>> owned;
  owned.push_back(makePointLight({0, 0, 0}, Color(100.0f)));
  owned.push_back(makeAreaLight(octahedron({0, 0, 0}, {0.1f, 0.1f, 0.1f})));
  owned.push_back(makePointLight({1, 0, 0}, Color(0.0f)));  // never picked
  owned.push_back(makePointLight({2, 0, 0}, Color(3.0f)));
  std::vector<const Light*> lights;
  for (auto& l : owned) lights.push_back(l.get());
  const LightSampler sampler(lights);
  EXPECT_FALSE(sampler.invertSample(2, 0.5f));
  EXPECT_FALSE(sampler.invertSample(4, 0.5f));
  for (bool fixed : {false, true}) {
    Pcg32 ra(41, 1), rb(41, 2);
    std::vector<float> a, b;
    for (int i = 0; i < 100000; ++i) {
      a.push_back(ra.uniform());
      float pmf = 0;
      const int index = sampler.sample(rb.uniform(), &pmf);
      const std::optional<float> u = sampler.invertSample(index, fixed ? 0.5f : rb.uniform());
      ASSERT_TRUE(u);
      float pmf2 = 0;
      ASSERT_EQ(sampler.sample(*u, &pmf2), index);
      ASSERT_EQ(pmf2, sampler.pmf(index));  // the Jacobian of eq. 40: the interval's width
      b.push_back(*u);
    }
    const test::TwoSampleResult r = test::twoSampleChi2(a, b, 1, 64, 0.01, kUniformityTests);
    EXPECT_EQ(r.passed, !fixed) << r.message;
  }
}

}  // namespace
}  // namespace mlt
