// BSDF and texture tests, and the chi-square framework's own tests (tests/support/chi2.h).
#include <gtest/gtest.h>

#include <cmath>

#include "common/core/rng.h"
#include "common/core/sampling.h"
#include "tests/support/chi2.h"

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

}  // namespace
}  // namespace mlt
