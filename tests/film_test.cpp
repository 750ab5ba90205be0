// Film: box filter bins, non-finite samples counted and dropped, merge = element-wise sum, develop scale.
#include "common/film/film.h"

#include "common/core/rng.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <utility>
#include <vector>

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

// Written blocks (pixel_buffer.h): a block no mutable access reached reads zero and is reported unwritten;
// operator[] marks its own block, data() every block, const access none; copies keep the marks.
TEST(PixelBuffer, MarksTheBlocksMutableAccessReaches) {
  for (const size_t n : {size_t(2000), size_t(300000)}) {  // malloc + memset, and calloc (>= 4 MB)
    constexpr size_t B = PixelBuffer::kBlock;
    PixelBuffer a(n);
    ASSERT_EQ(a.blockCount(), (n + B - 1) / B);
    EXPECT_EQ(a.blockSize(a.blockCount() - 1), n - (a.blockCount() - 1) * B);
    for (size_t b = 0; b < a.blockCount(); ++b) ASSERT_FALSE(a.blockWritten(b));
    a[B + 3].r = 2;  // block 1
    const PixelBuffer& ca = a;
    EXPECT_EQ(ca[5 * B].r, 0.0);  // a const read marks nothing
    a.writeBlock(3)[7].g = 5;     // block 3
    a.writeRange(6 * B - 1, 2);   // blocks 5 and 6, values untouched
    std::vector<size_t> marked;
    a.forEachWrittenBlock([&](size_t b, const RGBd* v, size_t count) {
      marked.push_back(b);
      EXPECT_EQ(v, ca.block(b));
      EXPECT_EQ(count, a.blockSize(b));
    });
    EXPECT_EQ(marked, (std::vector<size_t>{1, 3, 5, 6}));
    EXPECT_EQ(ca[B + 3].r, 2.0);
    EXPECT_EQ(ca[3 * B + 7].g, 5.0);
    EXPECT_EQ(ca[6 * B - 1].r, 0.0);
    PixelBuffer c = a;  // the copy has the values and the marks
    EXPECT_EQ(c.blockWritten(1) + c.blockWritten(2) + c.blockWritten(3), 2);
    EXPECT_EQ(static_cast<const PixelBuffer&>(c)[3 * B + 7].g, 5.0);
    c.data();  // raw mutable access: anything may be written
    for (size_t b = 0; b < c.blockCount(); ++b) ASSERT_TRUE(c.blockWritten(b));
  }
}

// develop and merge read only the written blocks; they must give what reading every value gives, bit for
// bit, on films with many layers of which each holds a few scattered splats (the mmlt job film's shape).
TEST(Film, DevelopAndMergeOfSparseLayersEqualTheDenseFormula) {
  for (const int w : {40, 600}) {  // 1600 pixels (small buffers), 600 x 400 (calloc'd, 5.8 MB per layer)
    const int h = w == 40 ? 40 : 400;
    Film a(w, h), b(w, h);
    Pcg32 rng(11, uint64_t(w));
    for (int i = 0; i < 3000; ++i) {
      Film& f = i % 3 == 0 ? b : a;
      const Vec2 p(rng.uniform() * w * (i % 5 == 0 ? 0.1f : 1.f), rng.uniform() * h);
      if (i % 7 == 0) f.addSample(p, Color(rng.uniform(), 1, 2));
      else f.addSplat(p, Color(rng.uniform(), rng.uniform(), 0.5f), size_t(1 + 2 * (i % 13)));
    }
    // The dense formula: every pixel, every layer.
    auto dense = [](const Film& f, const std::vector<double>& scales) {
      std::vector<Color> out(f.pixelCount());
      for (size_t i = 0; i < out.size(); ++i) {
        double r = 0, g = 0, bl = 0;
        if (f.pixelCounts()[i] > 0) {
          const double inv = 1.0 / f.pixelCounts()[i];
          r = f.pixelSums()[i].r * inv, g = f.pixelSums()[i].g * inv, bl = f.pixelSums()[i].b * inv;
        }
        for (size_t l = 0; l < f.splatLayerCount(); ++l) {
          if (!f.hasSplatLayer(l)) continue;
          const RGBd& v = f.splatLayer(l)[i];
          r += scales[l] * v.r, g += scales[l] * v.g, bl += scales[l] * v.b;
        }
        out[i] = Color(float(r), float(g), float(bl));
      }
      return out;
    };
    std::vector<double> scales(a.splatLayerCount() + 1);
    for (size_t l = 0; l < scales.size(); ++l) scales[l] = 0.37 * double(l + 1);
    Film before = a;
    a.merge(b);
    const Film& ca = a;
    const Film& cb = b;
    const Film& c0 = before;
    for (size_t l = 0; l < ca.splatLayerCount(); ++l) {  // merge = element-wise sum
      if (!ca.hasSplatLayer(l)) continue;
      for (size_t i = 0; i < ca.pixelCount(); ++i) {
        const double want = (c0.hasSplatLayer(l) ? c0.splatLayer(l)[i].r : 0.0) +
                            (cb.hasSplatLayer(l) ? cb.splatLayer(l)[i].r : 0.0);
        ASSERT_EQ(ca.splatLayer(l)[i].r, want) << "w " << w << " layer " << l << " pixel " << i;
      }
    }
    const std::vector<Color> got = ca.develop(scales), want = dense(ca, scales);
    ASSERT_EQ(got.size(), want.size());
    EXPECT_EQ(std::memcmp(got.data(), want.data(), got.size() * sizeof(Color)), 0) << "w " << w;
    // Scattered splats leave blocks unwritten, which is what the sparse reads skip.
    size_t unwritten = 0;
    for (size_t bk = 0; bk < ca.splatLayer(25).blockCount(); ++bk) unwritten += !ca.splatLayer(25).blockWritten(bk);
    if (w == 600) EXPECT_GT(unwritten, 0u);
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
