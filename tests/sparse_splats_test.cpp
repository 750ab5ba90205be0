// Sparse unit splats (common/film/sparse_splats.h): the same bits as a dense unit film, through
// quantization and the in-order merge, whatever the splats (repeats, off-film, non-finite), and a
// thread's scratch left zero for the next unit.
#include "common/film/sparse_splats.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>
#include <span>
#include <vector>

#include "common/job/job_types.h"
#include "common/mlt/develop.h"

namespace mlt {
namespace {

constexpr int W = 37, H = 23;  // not a power of two: row-major indexing is exercised

bool sameBuffer(std::span<const RGBd> a, std::span<const RGBd> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(RGBd)) == 0;
}

bool sameFilm(const Film& a, const Film& b) {
  if (a.width() != b.width() || a.height() != b.height() || a.nonFiniteSamples() != b.nonFiniteSamples()) return false;
  if (!sameBuffer(a.pixelSums(), b.pixelSums()) || a.splatLayers() != b.splatLayers()) return false;
  if (std::memcmp(a.pixelCounts().data(), b.pixelCounts().data(), a.pixelCounts().size() * sizeof(double)) != 0)
    return false;
  for (uint32_t l : a.splatLayers())
    if (!sameBuffer(a.splatLayer(l), b.splatLayer(l))) return false;
  return true;
}

struct Splat {
  Vec2 p;
  Color v;
};

// A chain-like stream: most splats near a wandering point, some anywhere, some off the film, a few
// non-finite; values spanning many orders of magnitude so that quantization rounds for real.
std::vector<Splat> splatStream(uint32_t seed, int n) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::vector<Splat> out;
  Vec2 at{W * 0.5f, H * 0.5f};
  for (int i = 0; i < n; ++i) {
    const float r = u(rng);
    if (r < 0.3f) at = {u(rng) * W, u(rng) * H};                       // a large step
    else at = {at.x + (u(rng) - 0.5f) * 2.f, at.y + (u(rng) - 0.5f) * 2.f};  // a small one
    Color v(std::ldexp(u(rng), int(u(rng) * 30) - 20), u(rng), u(rng) * 1e-7f);
    if (i % 97 == 0) v = Color(std::numeric_limits<float>::quiet_NaN(), 0, 0);
    if (i % 89 == 0) at = {-1.5f, at.y};  // off the film
    out.push_back({at, v});
  }
  return out;
}

PartialResult denseUnit(const std::vector<Splat>& splats, uint32_t layer, uint64_t seed, uint32_t unit) {
  PartialResult r;
  r.film = Film(W, H);
  for (const Splat& s : splats) r.film.addSplat(s.p, s.v, layer);
  quantizeFilm(r.film, seed, unit);
  r.units = {unit};
  return r;
}

PartialResult sparseUnit(const std::vector<Splat>& splats, uint32_t layer, uint64_t seed, uint32_t unit) {
  SparseSplatter splatter(W, H, layer);
  for (const Splat& s : splats) splatter.addSplat(s.p, s.v);
  PartialResult r;
  r.splats = splatter.take();
  quantizeSplats(r.splats, seed, unit);
  r.units = {unit};
  return r;
}

TEST(SparseSplats, UnitFilmIsBitIdenticalToTheDenseOne) {
  for (uint32_t layer : {0u, 1u, 4u}) {
    const std::vector<Splat> splats = splatStream(7 + layer, 5000);
    PartialResult dense = denseUnit(splats, layer, 11, 3);
    PartialResult sparse = sparseUnit(splats, layer, 11, 3);
    ASSERT_FALSE(sparse.splats.empty());
    const auto& l = sparse.splats.layers.at(0);
    EXPECT_TRUE(std::is_sorted(l.index.begin(), l.index.end()));
    EXPECT_LT(l.index.size(), size_t(W * H));  // sparse: not every pixel
    EXPECT_EQ(sparse.splats.nonFinite, dense.film.nonFiniteSamples());
    EXPECT_GT(sparse.splats.nonFinite, 0u);
    sparse.foldSplats();
    EXPECT_TRUE(sparse.splats.empty());
    EXPECT_TRUE(sameFilm(sparse.film, dense.film)) << "layer " << layer;
  }
}

TEST(SparseSplats, InOrderMergeOfUnitsIsBitIdenticalToTheDenseMerge) {
  PartialResult dense, sparse;
  dense.film = Film(W, H);
  sparse.film = Film(W, H);
  for (uint32_t unit = 0; unit < 12; ++unit) {
    const uint32_t layer = 1 + unit % 3;  // mmlt: one path-length layer per chain
    const std::vector<Splat> splats = splatStream(100 + unit, 800 + 100 * unit);
    dense.add(denseUnit(splats, layer, 5, unit));
    sparse.add(sparseUnit(splats, layer, 5, unit));
  }
  EXPECT_TRUE(sameFilm(sparse.film, dense.film));
  EXPECT_EQ(sparse.units, dense.units);
  // An empty accumulator takes its size from the first unit's splats.
  PartialResult fresh;
  fresh.add(sparseUnit(splatStream(1, 100), 2, 5, 0));
  EXPECT_EQ(fresh.film.width(), W);
  EXPECT_TRUE(fresh.film.hasSplatLayer(2));
}

// Whatever the unit's size: from fewer splats than the splatter defers (kDelay) to more pixels than it
// sorts (the list is then read off the touched bytes), with addAt between the splats, the unit equals the
// same calls on a dense film, in the same order, pixel for pixel.
TEST(SparseSplats, UnitsOfEverySizeEqualTheDenseCallsInOrder) {
  constexpr int W2 = 601, H2 = 499;  // sorted below W2 * H2 / 256 = 1171 touched pixels, scanned above
  for (int n : {1, 3, 8, 9, 17, 400, 3000, 60000}) {
    std::mt19937 rng{uint32_t(n)};
    std::uniform_real_distribution<float> u(0.f, 1.f);
    SparseSplatter splatter(W2, H2, 2);
    Film dense(W2, H2);
    PixelBuffer& layer = dense.splatLayer(2);
    Vec2 last{0.5f, 0.5f};
    for (int i = 0; i < n; ++i) {
      const Vec2 p{u(rng) * W2, u(rng) * H2};
      if (i % 13 == 5) {  // an exact add (the b strata's kind) on the pixel of splats still deferred
        const size_t pixel = size_t(filmPixelIndex(last, W2, H2));
        const RGBd v{u(rng), 1e-9 * u(rng), 3.0};
        splatter.addAt(pixel, v);
        layer[pixel] += v;
        continue;
      }
      const Color v(std::ldexp(u(rng), int(u(rng) * 40) - 20), u(rng), 1.f);
      splatter.addSplat(p, v);
      dense.addSplat(p, v, 2);
      last = p;
      if (i % 3 == 0) {  // the same pixel again: a rejected proposal's repeat
        splatter.addSplat(p, v * 3.f);
        dense.addSplat(p, v * 3.f, 2);
      }
    }
    const SparseSplats taken = splatter.take();
    const auto& l = taken.layers.at(0);
    ASSERT_TRUE(std::is_sorted(l.index.begin(), l.index.end())) << n << " splats";
    ASSERT_TRUE(std::adjacent_find(l.index.begin(), l.index.end()) == l.index.end()) << n << " splats";
    size_t listed = 0;
    for (size_t pixel = 0; pixel < layer.size(); ++pixel) {
      const bool isListed = listed < l.index.size() && l.index[listed] == pixel;
      const RGBd want = layer[pixel];
      const RGBd got = isListed ? l.value[listed] : RGBd{};
      ASSERT_EQ(std::memcmp(&want, &got, sizeof(RGBd)), 0) << n << " splats, pixel " << pixel;
      if (!isListed) {
        ASSERT_TRUE(want.r == 0 && want.g == 0 && want.b == 0) << n << " splats, pixel " << pixel;
      }
      listed += isListed;
    }
    EXPECT_EQ(listed, l.index.size());
  }
}

TEST(SparseSplats, ALayerWithoutPixelsIsStillAllocated) {
  SparseSplatter splatter(W, H, 3);
  splatter.addSplat({-5.f, 2.f}, Color(1));  // off the film only
  PartialResult r;
  r.splats = splatter.take();
  r.foldSplats();
  ASSERT_TRUE(r.film.hasSplatLayer(3));  // as the dense unit film had it
  for (const RGBd& v : r.film.splatLayer(3)) EXPECT_EQ(v.r, 0.0);
}

TEST(SparseSplats, SizeMismatchIsRefused) {
  PartialResult acc;
  acc.film = Film(W + 1, H);
  EXPECT_THROW(acc.add(sparseUnit(splatStream(2, 10), 1, 5, 0)), std::invalid_argument);
  EXPECT_TRUE(acc.units.empty());  // nothing changed
}

TEST(SparseSplats, ScratchIsZeroForTheNextUnitEvenAfterAnAbandonedOne) {
  const std::vector<Splat> splats = splatStream(9, 2000);
  const PartialResult first = sparseUnit(splats, 1, 5, 0);
  {
    SparseSplatter abandoned(W, H, 1);  // a chain that threw: never taken
    for (const Splat& s : splatStream(10, 3000)) abandoned.addSplat(s.p, s.v);
  }
  const PartialResult again = sparseUnit(splats, 1, 5, 0);
  EXPECT_EQ(first.splats.layers[0].index, again.splats.layers[0].index);
  EXPECT_TRUE(sameBuffer(first.splats.layers[0].value, again.splats.layers[0].value));
}

TEST(SparseSplats, TwoSplattersAliveOnOneThreadDoNotShareTheScratch) {
  SparseSplatter a(W, H, 1), b(W, H, 2);
  a.addSplat({1.5f, 1.5f}, Color(1));
  b.addSplat({1.5f, 1.5f}, Color(2));
  const SparseSplats sa = a.take(), sb = b.take();
  ASSERT_EQ(sa.layers[0].value.size(), 1u);
  ASSERT_EQ(sb.layers[0].value.size(), 1u);
  EXPECT_EQ(sa.layers[0].value[0].r, 1.0);
  EXPECT_EQ(sb.layers[0].value[0].r, 2.0);
  EXPECT_EQ(sb.layers[0].layer, 2u);
}

}  // namespace
}  // namespace mlt
