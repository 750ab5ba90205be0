// The ideal chain's relMSE (tools/eval/ideal_chain.h (I1)): the closed forms on a constant image, the
// Cauchy-Schwarz optimum, a Monte Carlo check of (I1) against simulated Poisson visits, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "common/core/rng.h"
#include "tools/eval/ideal_chain.h"
#include "tools/eval/metrics.h"

namespace mlt::eval {
namespace {

std::vector<Color> randomImage(int pixels, uint64_t seed) {
  Pcg32 rng(seed, 7);
  std::vector<Color> img(pixels);
  for (Color& c : img) {
    // Brightness spread over three decades, colours unequal, some pixels black.
    const float scale = rng.uniform() < 0.1f ? 0.0f : std::pow(10.0f, 3 * rng.uniform() - 2);
    c = Color(scale * (0.2f + rng.uniform()), scale * (0.2f + rng.uniform()), scale * (0.2f + rng.uniform()));
  }
  return img;
}

// Poisson(mean) by counting unit-rate exponential arrivals before `mean` (exact; fine for small means).
int poisson(Pcg32& rng, double mean) {
  int n = 0;
  double t = -std::log(1.0 - rng.uniformDouble());
  while (t < mean) {
    ++n;
    t -= std::log(1.0 - rng.uniformDouble());
  }
  return n;
}

TEST(IdealChain, ConstantGreyImageGivesTheClosedFormForEveryTarget) {
  const int P = 100;
  const double N = 5000, eps = 0.01;
  const std::vector<Color> img(P, Color(1.0f));
  const IdealChainBounds b = idealChainBounds(img, N, eps);
  const double expected = P * (1 / (1 + eps)) / N;  // sum_j a_j / N with a_j = 1 / (1 + eps)
  EXPECT_NEAR(b.luminance, expected, 1e-9 * expected);
  EXPECT_NEAR(b.uniform, expected, 1e-9 * expected);
  EXPECT_NEAR(b.best, expected, 1e-9 * expected);
}

TEST(IdealChain, BestTargetIsTheMinimumOverTargets) {
  const std::vector<Color> img = randomImage(256, 3);
  const double N = 1e5;
  const IdealChainBounds b = idealChainBounds(img, N);
  EXPECT_LT(b.best, b.luminance);
  EXPECT_LT(b.best, b.uniform);
  // Any perturbation of the best target costs: (I1) is convex in c with its minimum at sqrt(a_j).
  std::vector<double> best(img.size());
  for (size_t j = 0; j < img.size(); ++j) {
    double a = 0;
    for (float x : {img[j].r, img[j].g, img[j].b}) a += double(x) * x / (double(x) * x + 0.01);
    best[j] = std::sqrt(a / 3);
  }
  EXPECT_NEAR(idealChainRelMse(img, best, N), b.best, 1e-12);
  Pcg32 rng(11, 1);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> c = best;
    for (double& v : c) v *= std::exp(0.5 * (rng.uniformDouble() - 0.5));
    EXPECT_GT(idealChainRelMse(img, c, N), b.best);
  }
}

TEST(IdealChain, MatchesSimulatedPoissonVisits) {
  // The model of (I1) run for real: pixel j visited n_j ~ Poisson(N c_j / C) times, each visit worth
  // I_j C / (N c_j), the image measured by the harness's relMSE. The mean over trials must agree with
  // (I1) within 4 standard errors of that mean.
  const std::vector<Color> img = randomImage(64, 5);
  const double N = 6400;
  std::vector<double> c(img.size());
  double C = 0;
  for (size_t j = 0; j < img.size(); ++j) C += c[j] = std::fmax(0.0, double(luminance(img[j])));
  const double predicted = idealChainRelMse(img, c, N);
  Pcg32 rng(2026, 12);
  const int trials = 3000;
  double sum = 0, sum2 = 0;
  for (int t = 0; t < trials; ++t) {
    std::vector<Color> est(img.size());
    for (size_t j = 0; j < img.size(); ++j) {
      if (c[j] == 0) continue;
      const double mean = N * c[j] / C;
      est[j] = img[j] * float(poisson(rng, mean) / mean);
    }
    const double r = computeMetrics(est, img).relMSE;
    sum += r;
    sum2 += r * r;
  }
  const double mean = sum / trials, se = std::sqrt((sum2 / trials - mean * mean) / (trials - 1));
  EXPECT_NEAR(mean, predicted, 4 * se) << "predicted " << predicted << ", simulated " << mean << " +- " << se;
  EXPECT_LT(se, 0.05 * predicted);  // the check resolves a 20% error in (I1)
}

TEST(IdealChain, UnvisitedLitPixelIsInfiniteAndBadInputIsRefused) {
  std::vector<Color> img = {Color(1.0f), Color(0.0f), Color(0.5f)};
  EXPECT_EQ(idealChainRelMse(img, {1, 0, 0}, 10), std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isfinite(idealChainRelMse(img, {1, 0, 1}, 10)));  // a black pixel costs nothing
  EXPECT_THROW(idealChainRelMse(img, {1, 1}, 10), std::invalid_argument);
  EXPECT_THROW(idealChainRelMse(img, {0, 0, 0}, 10), std::invalid_argument);
  EXPECT_THROW(idealChainRelMse(img, {1, -1, 1}, 10), std::invalid_argument);
  EXPECT_THROW(idealChainRelMse(img, {1, 1, 1}, 0), std::invalid_argument);
  EXPECT_THROW(idealChainRelMse({}, {}, 10), std::invalid_argument);
  // The harness's figure is -1, not an exception, where there is nothing to compare with.
  EXPECT_EQ(idealLuminanceChainRelMse(std::vector<Color>(4, Color(0.0f)), 100), -1);
  EXPECT_EQ(idealLuminanceChainRelMse(img, 0), -1);
  EXPECT_EQ(idealLuminanceChainRelMse({Color(1.0f), Color(-1.0f, 0.0f, 0.0f)}, 10), -1);  // lit, zero luminance
  EXPECT_DOUBLE_EQ(idealLuminanceChainRelMse(img, 10), idealChainBounds(img, 10).luminance);
}

}  // namespace
}  // namespace mlt::eval
