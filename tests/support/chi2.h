// Reusable chi-square goodness-of-fit tests for sampling routines (after Mitsuba's chi2 test).
//
// A sampler draws `samples` points; they are histogrammed into bins. The expected count of each bin is
// samples * (integral of the claimed density over the bin), computed by nested adaptive Simpson
// quadrature. A sampler may fail (return nullopt, "absorbed"): the density is then a sub-density whose
// integral is the success probability, and the absorbed samples form one more category with expected
// count samples * (1 - integral). Bins whose expected count is below 5 are pooled. The statistic's
// p-value comes from the chi-square CDF (regularized incomplete gamma function, implemented here).
// The test passes when pValue > 1 - (1 - significance)^(1 / testCount) (Sidak correction for running
// testCount tests in one suite). A sample that lands where the density integrates to zero, or outside
// the domain, fails the test outright.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "common/core/rng.h"
#include "common/core/vec.h"

namespace mlt::test {

struct Chi2Result {
  bool passed = false;
  double pValue = 0;
  double statistic = 0;
  int dof = 0;
  std::string message;  // human-readable summary (also on success): statistic, dof, p, worst bins
};

// Goodness of fit of a direction sampler against its solid-angle density over the whole sphere.
// Bins are uniform in (cos theta, phi) with cos theta in [-1, 1] and phi in [0, 2 pi); use an even
// thetaBins so that the horizon (cos theta = 0, where hemispherical densities jump) is a bin edge.
Chi2Result chi2TestSphere(const std::function<std::optional<Vec3>(Pcg32&)>& sample,
                          const std::function<double(const Vec3&)>& pdfW, int thetaBins = 20, int phiBins = 40,
                          int samples = 200000, double significance = 0.01, int testCount = 1, uint64_t seed = 1);

// The same for a sampler of points in the rectangle [lo.x, hi.x] x [lo.y, hi.y] with density pdf(x, y)
// (with respect to dx dy). Points outside the rectangle fail the test.
Chi2Result chi2Test2D(const std::function<std::optional<Vec2>(Pcg32&)>& sample,
                      const std::function<double(Vec2)>& pdf, Vec2 lo, Vec2 hi, int xBins, int yBins, int samples,
                      double significance = 0.01, int testCount = 1, uint64_t seed = 1);

// Building blocks, exposed for tests of the framework itself.
// Regularized upper incomplete gamma function Q(a, x) = Gamma(a, x) / Gamma(a).
double regularizedGammaQ(double a, double x);
// P(X >= stat) for X ~ chi-square with dof degrees of freedom.
double chi2SurvivalProbability(double stat, int dof);
// Nested adaptive Simpson integral of f over [x0,x1] x [y0,y1] with absolute tolerance eps.
double adaptiveSimpson2D(const std::function<double(double, double)>& f, double x0, double x1, double y0,
                         double y1, double eps);

}  // namespace mlt::test
