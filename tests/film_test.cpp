// Film: box filter bins, non-finite samples counted and dropped, merge = element-wise sum, develop scale.
#include "common/film/film.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <span>
#include <utility>

namespace mlt {
namespace {

// The film's buffers (pixel_buffer.h): zero at first whatever the allocator reused, independent copies,
// moves that leave the source empty, and a layer allocated on first use reads zero where nothing wrote.
// Both allocation paths: 100000 pixels (2.4 MB, malloc + memset) and 300000 (7.2 MB, calloc).
TEST(PixelBuffer, StartsZeroCopiesAndMovesLikeAValue) {
  for (int round = 0; round < 6; ++round) {  // later rounds may get memory the previous ones freed
    const size_t n = round % 2 == 0 ? 100000 : 300000;
    PixelBuffer a(n);
    ASSERT_EQ(a.size(), n);
    for (const RGBd& v : a) ASSERT_TRUE(v.r == 0 && v.g == 0 && v.b == 0);
    for (size_t i = 0; i < a.size(); i += 7) a[i] = RGBd{double(i), 1, -2};
    PixelBuffer b = a;  // a copy: equal, then independent
    ASSERT_EQ(b.size(), a.size());
    EXPECT_EQ(b[7].r, 7.0);
    b[7].r = 5;
    EXPECT_EQ(a[7].r, 7.0);
    b = b;  // self-assignment keeps the values
    EXPECT_EQ(b[7].r, 5.0);
    PixelBuffer c = std::move(b);
    EXPECT_TRUE(b.empty());
    EXPECT_EQ(b.data(), nullptr);
    EXPECT_EQ(c[7].r, 5.0);
    const std::span<const RGBd> view = c;
    EXPECT_EQ(view.size(), c.size());
    EXPECT_EQ(view.data(), c.data());
  }
  EXPECT_TRUE(PixelBuffer().empty());
  EXPECT_TRUE(PixelBuffer(0).empty());
  Film f(300, 200);
  f.addSplat({10.5f, 20.5f}, Color(1, 2, 3), 9);
  const PixelBuffer& layer = f.splatLayer(9);
  for (size_t i = 0; i < layer.size(); ++i) {
    const bool hit = i == size_t(20 * 300 + 10);
    ASSERT_EQ(layer[i].r, hit ? 1.0 : 0.0) << i;
    ASSERT_EQ(layer[i].b, hit ? 3.0 : 0.0) << i;
  }
}

TEST(Film, BoxFilterBinsByFloorOfRasterPosition) {
  Film film(4, 3);
  film.addSample({0.0f, 0.0f}, Color(1, 2, 3));
  film.addSample({0.999f, 0.999f}, Color(1, 0, 0));  // still pixel (0,0)
  film.addSample({1.0f, 0.0f}, Color(5));            // pixel (1,0)
  film.addSample({3.5f, 2.5f}, Color(7));            // last pixel
  EXPECT_EQ(film.pixelCounts()[0], 2.0);
  EXPECT_EQ(film.pixelSums()[0].r, 2.0);
  EXPECT_EQ(film.pixelSums()[0].g, 2.0);
  EXPECT_EQ(film.pixelSums()[0].b, 3.0);
  EXPECT_EQ(film.pixelCounts()[1], 1.0);
  EXPECT_EQ(film.pixelSums()[1].g, 5.0);
  EXPECT_EQ(film.pixelCounts()[11], 1.0);
  EXPECT_EQ(film.pixelSums()[11].b, 7.0);
  // Splats: same binning, separate buffer.
  film.addSplat({2.2f, 1.7f}, Color(4));
  EXPECT_EQ(film.splatSums()[1 * 4 + 2].r, 4.0);
  EXPECT_EQ(film.pixelCounts()[1 * 4 + 2], 0.0);
}

TEST(Film, OffFilmSamplesAndSplatsAreIgnored) {
  Film film(2, 2);
  for (Vec2 p : {Vec2(-0.01f, 0.5f), Vec2(0.5f, -0.01f), Vec2(2.0f, 0.5f), Vec2(0.5f, 2.0f),
                 Vec2(std::numeric_limits<float>::quiet_NaN(), 0.5f)}) {
    film.addSample(p, Color(1));
    film.addSplat(p, Color(1));
  }
  for (size_t i = 0; i < film.pixelCount(); ++i) {
    EXPECT_EQ(film.pixelCounts()[i], 0.0);
    EXPECT_EQ(film.pixelSums()[i].r, 0.0);
    EXPECT_EQ(film.splatSums()[i].r, 0.0);
  }
  EXPECT_EQ(film.nonFiniteSamples(), 0u);
}

TEST(Film, NonFiniteValuesAreCountedAndDropped) {
  Film film(2, 1);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  film.addSample({0.5f, 0.5f}, Color(nan, 0, 0));
  film.addSample({0.5f, 0.5f}, Color(0, inf, 0));
  film.addSplat({1.5f, 0.5f}, Color(0, 0, -inf));
  film.addSample({0.5f, 0.5f}, Color(1));
  EXPECT_EQ(film.nonFiniteSamples(), 3u);
  EXPECT_EQ(film.pixelCounts()[0], 1.0);  // the dropped samples do not count
  EXPECT_EQ(film.pixelSums()[0].r, 1.0);
  EXPECT_EQ(film.splatSums()[1].b, 0.0);
  for (const Color& c : film.develop(1.0)) EXPECT_TRUE(c.isFinite());
}

TEST(Film, MergeIsElementWiseSum) {
  Film a(3, 2), b(3, 2);
  a.addSample({0.5f, 0.5f}, Color(1, 2, 3));
  a.addSplat({2.5f, 1.5f}, Color(0.25f));
  b.addSample({0.5f, 0.5f}, Color(3, 2, 1));
  b.addSample({1.5f, 1.5f}, Color(8));
  b.addSplat({2.5f, 1.5f}, Color(0.5f));
  b.addSample({0.5f, 0.5f}, Color(std::numeric_limits<float>::quiet_NaN()));
  a.merge(b);
  EXPECT_EQ(a.pixelCounts()[0], 2.0);
  EXPECT_EQ(a.pixelSums()[0].r, 4.0);
  EXPECT_EQ(a.pixelSums()[0].b, 4.0);
  EXPECT_EQ(a.pixelCounts()[4], 1.0);
  EXPECT_EQ(a.splatSums()[5].g, 0.75);
  EXPECT_EQ(a.nonFiniteSamples(), 1u);
  Film wrong(2, 3);
  EXPECT_THROW(a.merge(wrong), std::invalid_argument);
}

TEST(Film, DevelopIsMeanPlusScaledSplats) {
  Film film(2, 1);
  film.addSample({0.5f, 0.5f}, Color(1, 2, 3));
  film.addSample({0.5f, 0.5f}, Color(3, 2, 1));
  film.addSplat({0.5f, 0.5f}, Color(4, 0, 0));
  film.addSplat({1.5f, 0.5f}, Color(0, 8, 0));
  const std::vector<Color> img = film.develop(0.25);
  ASSERT_EQ(img.size(), 2u);
  EXPECT_FLOAT_EQ(img[0].r, 2.0f + 1.0f);
  EXPECT_FLOAT_EQ(img[0].g, 2.0f);
  EXPECT_FLOAT_EQ(img[0].b, 2.0f);
  // A pixel without samples develops to its splats alone (no division by a zero count).
  EXPECT_FLOAT_EQ(img[1].r, 0.0f);
  EXPECT_FLOAT_EQ(img[1].g, 2.0f);
}

TEST(Film, RejectsEmptySize) {
  EXPECT_THROW(Film(0, 4), std::invalid_argument);
  EXPECT_THROW(Film(4, -1), std::invalid_argument);
}

}  // namespace
}  // namespace mlt

namespace mlt {
namespace {

TEST(Film, SplatLayersMergeAndDevelopEachWithItsOwnScale) {
  Film a(3, 2), b(3, 2);
  a.addSplat({0.5f, 0.5f}, Color(1), 0);
  a.addSplat({0.5f, 0.5f}, Color(2), 3);  // layer 3 only on a
  b.addSplat({0.5f, 0.5f}, Color(4), 5);  // layer 5 only on b
  b.addSplat({0.5f, 0.5f}, Color(8), 3);
  EXPECT_FALSE(a.hasSplatLayer(1));
  EXPECT_TRUE(a.hasSplatLayer(3));
  a.merge(b);
  EXPECT_EQ(a.splatLayer(3)[0].r, 10.0);
  EXPECT_EQ(a.splatLayer(5)[0].g, 4.0);
  EXPECT_FALSE(a.hasSplatLayer(4));
  // Pixel 0: 1 * s0 + 10 * s3 + 4 * s5.
  const std::vector<Color> img = a.develop({0.5, 0, 0, 0.25, 0, 2});
  EXPECT_FLOAT_EQ(img[0].r, 0.5f + 2.5f + 8.f);
  EXPECT_FLOAT_EQ(img[1].r, 0.f);
  // A layer that holds sums but has no scale is an error, not a silently dropped component.
  EXPECT_THROW(a.develop({1, 1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(a.develop(1.0), std::invalid_argument);
  const Film& c = a;
  EXPECT_THROW(c.splatLayer(4), std::out_of_range);
}

}  // namespace
}  // namespace mlt
