// tools/eval/bands.h: the relMSE and the ideal chain's (I1) split by the reference's brightness.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <vector>

#include "tools/eval/bands.h"
#include "tools/eval/ideal_chain.h"
#include "tools/eval/metrics.h"

using namespace mlt;
using namespace mlt::eval;

namespace {

// P pixels of distinct grey levels 1..P (luminance = the level), in a shuffled order.
std::vector<Color> shuffledRamp(int P, uint32_t seed) {
  std::vector<Color> img(size_t(P), Color(0.0f));
  std::vector<int> level(static_cast<size_t>(P), 0);
  std::iota(level.begin(), level.end(), 1);
  std::mt19937 rng(seed);
  std::shuffle(level.begin(), level.end(), rng);
  for (size_t j = 0; j < img.size(); ++j) img[j] = Color(0.01f * float(level[j]));
  return img;
}

std::vector<Color> noisy(const std::vector<Color>& ref, double sigma, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, float(sigma));
  std::vector<Color> out = ref;
  for (Color& c : out) c = Color(c.r * (1 + n(rng)), c.g * (1 + n(rng)), c.b * (1 + n(rng)));
  return out;
}

}  // namespace

TEST(Bands, QuantileSizesAndOrder) {
  const int P = 1000;
  const std::vector<Color> ref = shuffledRamp(P, 3);
  const std::vector<int> band = brightnessBands(ref);
  ASSERT_EQ(band.size(), size_t(P));
  int count[kBands] = {};
  for (size_t j = 0; j < band.size(); ++j) {
    ASSERT_GE(band[j], 0);
    ASSERT_LT(band[j], kBands);
    ++count[band[j]];
    // Level l (1..P) has rank l - 1: band 0 holds ranks [0, 500), 1 [500, 900), 2 [900, 990), 3 the rest.
    const int rank = int(std::lround(ref[j].r / 0.01f)) - 1;
    const int expected = rank < 500 ? 0 : rank < 900 ? 1 : rank < 990 ? 2 : 3;
    EXPECT_EQ(band[j], expected) << "pixel " << j << " rank " << rank;
  }
  EXPECT_EQ(count[0], 500);
  EXPECT_EQ(count[1], 400);
  EXPECT_EQ(count[2], 90);
  EXPECT_EQ(count[3], 10);
  // Ties (a constant image) are ranked by index: the first half is the darkest band.
  const std::vector<int> flat = brightnessBands(std::vector<Color>(size_t(P), Color(0.5f)));
  EXPECT_EQ(flat[0], 0);
  EXPECT_EQ(flat[499], 0);
  EXPECT_EQ(flat[500], 1);
  EXPECT_EQ(flat[P - 1], 3);
  EXPECT_THROW(brightnessBands({}), std::invalid_argument);
  EXPECT_EQ(bandName(0), "darkest 50%");
  EXPECT_EQ(bandName(3), "brightest 1%");
  EXPECT_THROW(bandName(4), std::invalid_argument);
}

TEST(Bands, RelMseBandsAddUpToTheRunsRelMse) {
  const std::vector<Color> ref = shuffledRamp(4096, 5);
  const std::vector<int> band = brightnessBands(ref);
  std::vector<Color> img = noisy(ref, 0.1, 7);
  img[17].g = std::numeric_limits<float>::quiet_NaN();  // excluded, as computeMetrics excludes it
  const ImageMetrics m = computeMetrics(img, ref);
  ASSERT_EQ(m.nonFinite, 1u);
  const BandValues b = bandRelMse(img, ref, band);
  double sum = 0;
  for (double v : b) {
    EXPECT_GT(v, 0);
    sum += v;
  }
  EXPECT_NEAR(sum, m.relMSE, 1e-12 * m.relMSE);
  EXPECT_THROW(bandRelMse(img, std::vector<Color>(10), band), std::invalid_argument);
  std::vector<int> bad = band;
  bad[3] = kBands;
  EXPECT_THROW(bandRelMse(img, ref, bad), std::invalid_argument);
}

TEST(Bands, ErrorIsFoundInTheBandThatHoldsIt) {
  const std::vector<Color> ref = shuffledRamp(2000, 11);
  const std::vector<int> band = brightnessBands(ref);
  for (int target = 0; target < kBands; ++target) {
    std::vector<Color> img = ref;
    for (size_t j = 0; j < img.size(); ++j)
      if (band[j] == target) img[j] *= 1.5f;
    const BandValues b = bandRelMse(img, ref, band);
    for (int k = 0; k < kBands; ++k) {
      if (k == target) EXPECT_GT(b[size_t(k)], 0) << "band " << k;
      else EXPECT_EQ(b[size_t(k)], 0) << "band " << k << " (error put in band " << target << ")";
    }
  }
}

TEST(Bands, IdealBandsSplitTheIdealChainsRelMse) {
  const std::vector<Color> ref = shuffledRamp(4096, 13);
  const std::vector<int> band = brightnessBands(ref);
  const double N = 1e6;
  const BandValues b = idealLuminanceChainBands(ref, band, N);
  const double total = idealLuminanceChainRelMse(ref, N);
  ASSERT_GT(total, 0);
  double sum = 0;
  for (double v : b) sum += v;
  EXPECT_NEAR(sum, total, 1e-12 * total);
  // Closed form on a constant image: every term is a P / N (C = P L, c_j = L), so band k holds
  // (its pixel count) a / N, a = I^2 / (I^2 + eps).
  const int P = 1000;
  const std::vector<Color> flat(size_t(P), Color(0.5f));
  const BandValues f = idealLuminanceChainBands(flat, brightnessBands(flat), N);
  const double a = 0.25 / (0.25 + 1e-2);
  const double counts[kBands] = {500, 400, 90, 10};
  for (int k = 0; k < kBands; ++k) EXPECT_NEAR(f[size_t(k)], counts[k] * a / N, 1e-12) << "band " << k;
  // Nothing to compare with: every band -1, as idealLuminanceChainRelMse is.
  const std::vector<Color> black(size_t(P), Color(0.0f));
  for (double v : idealLuminanceChainBands(black, brightnessBands(black), N)) EXPECT_EQ(v, -1);
  for (double v : idealLuminanceChainBands(ref, band, 0)) EXPECT_EQ(v, -1);
  EXPECT_THROW(idealLuminanceChainBands(ref, std::vector<int>(5), N), std::invalid_argument);
}
