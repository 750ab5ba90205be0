// The job API's sample-based half with a stand-in path evaluator (the real ones are tested by the
// integrators' tests): method names, PartialResult merging, plan splitting, thread-count independence,
// and the light-tracing normalization P / N.
#include "common/job/sample_job.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <bit>
#include <cmath>
#include <cstring>

#include "common/methods/registry.h"
#include "common/mlt/develop.h"
#include "common/sampler/sample_source.h"

namespace mlt {
namespace {

// A deterministic stand-in: a camera sample worth (u0, u1, 1) (t = 2) and, with probability 1/2, a t = 1
// splat of value 1 at a uniformly random film position (the second case lands anywhere on the film).
class FakeEvaluator final : public PathEvaluator {
 public:
  // splatsOnly: a light tracer's evaluator (every splat goes to the splat sums), like lt's.
  FakeEvaluator(int w, int h, bool splatsOnly = false) : w_(w), h_(h), splatsOnly_(splatsOnly) {}
  bool splatsOnly() const override { return splatsOnly_; }
  void evaluate(SampleSource& src, const Vec2* pixel, PathContribution& out) const override {
    src.startStream(Stream::Camera);
    const Vec2 u = src.next2D();
    out.cameraRaster = Vec2(pixel->x + u.x, pixel->y + u.y);
    out.splats.push_back({out.cameraRaster, Color(u.x, u.y, 1.f), 0, 2});
    src.startStream(Stream::Light);
    const float pick = src.next1D();
    const Vec2 p = src.next2D();
    if (pick < 0.5f) out.splats.push_back({Vec2(p.x * w_, p.y * h_), Color(1.f), 1, 1});
  }

 private:
  int w_, h_;
  bool splatsOnly_;
};

RenderSettings settingsFor(std::string m, int spp, int w, int h) {
  RenderSettings s;
  s.method = m;
  s.spp = spp;
  s.width = w;
  s.height = h;
  s.seed = 42;
  return s;
}

void expectBitIdentical(const Film& a, const Film& b) {
  ASSERT_EQ(a.pixelCount(), b.pixelCount());
  auto bits = [](double d) { return std::bit_cast<uint64_t>(d); };
  for (size_t i = 0; i < a.pixelCount(); ++i) {
    ASSERT_EQ(bits(a.pixelSums()[i].r), bits(b.pixelSums()[i].r)) << i;
    ASSERT_EQ(bits(a.pixelSums()[i].g), bits(b.pixelSums()[i].g)) << i;
    ASSERT_EQ(bits(a.pixelCounts()[i]), bits(b.pixelCounts()[i])) << i;
    ASSERT_EQ(bits(a.splatSums()[i].r), bits(b.splatSums()[i].r)) << i;
  }
}

TEST(JobApi, RegistryFindsEveryBuiltInMethodByName) {
  for (std::string m : {"pt", "lt", "bdpt", "pssmlt", "pssmlt-bdpt", "mmlt"}) EXPECT_EQ(findMethod(m).name(), m);
  EXPECT_THROW(findMethod("PT"), std::invalid_argument);
  try {
    findMethod("metropolis");
    ADD_FAILURE() << "an unknown method was found";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("metropolis"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("pssmlt-bdpt"), std::string::npos) << e.what();  // lists the names
  }
  EXPECT_FALSE(isMarkovChainMethod("bdpt"));
  EXPECT_TRUE(isMarkovChainMethod("mmlt"));
}

TEST(JobApi, PlanSplitsSamplesIntoUnitsCoveringEverySampleOnce) {
  RenderSettings s = settingsFor("pt", 37, 8, 8);
  JobPlan auto_ = planSampleJob(s);
  EXPECT_EQ(auto_.settings.samplesPerUnit, 3);  // ceil(37 / 16)
  s.samplesPerUnit = 5;
  const JobPlan plan = planSampleJob(s);
  uint32_t next = 0;
  for (size_t i = 0; i < plan.units.size(); ++i) {
    EXPECT_EQ(plan.units[i].index, i);
    EXPECT_EQ(plan.units[i].sampleBegin, next);
    EXPECT_LE(plan.units[i].sampleEnd - plan.units[i].sampleBegin, 5u);
    next = plan.units[i].sampleEnd;
  }
  EXPECT_EQ(next, 37u);
  s.spp = 0;
  EXPECT_THROW(planSampleJob(s), std::invalid_argument);
}

TEST(JobApi, PartialResultAddMergesAndRejectsDuplicates) {
  RenderSettings s = settingsFor("bdpt", 4, 20, 9);
  s.samplesPerUnit = 1;
  const JobPlan plan = planSampleJob(s);
  const FakeEvaluator eval(20, 9);
  std::vector<PartialResult> parts;
  for (const WorkUnit& u : plan.units) parts.push_back(runSampleUnit(eval, plan, u));

  PartialResult merged;
  for (const PartialResult& p : parts) merged.add(p);
  EXPECT_EQ(merged.units, (std::vector<uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(merged.samples, 4u * 20 * 9);
  for (size_t i = 0; i < merged.film.pixelCount(); ++i) EXPECT_EQ(merged.film.pixelCounts()[i], 4.0);

  // The same units merged as pairs ((0+1) + (2+3)) in index order: the same units, same counts.
  PartialResult a, b;
  a.add(parts[0]);
  a.add(parts[1]);
  b.add(parts[2]);
  b.add(parts[3]);
  PartialResult pairs;
  pairs.add(a);
  pairs.add(b);
  EXPECT_EQ(pairs.units, merged.units);
  EXPECT_EQ(pairs.samples, merged.samples);

  // A unit already included is rejected, and the result is left untouched.
  const std::vector<Color> before = merged.film.develop(1.0);
  EXPECT_THROW(merged.add(parts[2]), std::invalid_argument);
  EXPECT_THROW(pairs.add(a), std::invalid_argument);
  EXPECT_EQ(merged.samples, 4u * 20 * 9);
  const std::vector<Color> after = merged.film.develop(1.0);
  for (size_t i = 0; i < before.size(); ++i) EXPECT_EQ(before[i].r, after[i].r);
}

TEST(JobApi, SampleUnitIsBitIdenticalWhateverTheThreadCount) {
  // 40x37: partial tiles at the edges and more than one tile group would need > 64 tiles, so also a
  // wide film.
  for (auto [w, h] : {std::pair{40, 37}, std::pair{300, 70}}) {
    RenderSettings s = settingsFor("bdpt", 3, w, h);
    const JobPlan plan = planSampleJob(s);
    const FakeEvaluator eval(w, h);
    PartialResult one, two;
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
      for (const WorkUnit& u : plan.units) one.add(runSampleUnit(eval, plan, u));
    }
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 4);
      for (const WorkUnit& u : plan.units) two.add(runSampleUnit(eval, plan, u));
    }
    expectBitIdentical(one.film, two.film);
  }
}

// PixelSampling (the pass of the lights seen directly): stratified, a pixel's n samples lie at its rotated
// Hammersley points, so their positions in the pixel average to its centre within half a stratum, 0.5 / n
// on either axis (the fake evaluator's camera sample is worth its position (u0, u1); a rotation by r moves
// the mean by r less the points it wraps over the edge, over n), where hashed points leave each pixel's
// mean off by ~0.29 / sqrt(n); a pixel of multiplicity m gets n = m spp of them. Each point is uniform on
// its own, so the first half of the samples (one unit of two) is still unbiased over the film.
TEST(JobApi, StratifiedPixelPointsCoverEachPixelEvenly) {
  constexpr int kW = 20, kH = 15, kSpp = 16;
  RenderSettings s = settingsFor("pt", kSpp, kW, kH);
  s.samplesPerUnit = kSpp / 2;
  const JobPlan plan = planSampleJob(s);
  ASSERT_EQ(plan.units.size(), 2u);
  const FakeEvaluator eval(kW, kH);
  PixelSampling sampling;
  sampling.multiplicity.assign(size_t(kW) * kH, 1);
  for (size_t i = 0; i < sampling.multiplicity.size(); i += 7) sampling.multiplicity[i] = 4;
  auto worst = [&](PixelSampling::Points points) {
    sampling.points = points;
    PartialResult all;
    for (const WorkUnit& u : plan.units) all.add(runSampleUnit(eval, plan, u, nullptr, &sampling));
    double off = 0;  // relative to half a stratum
    for (size_t i = 0; i < all.film.pixelCount(); ++i) {
      const double n = double(kSpp) * sampling.multiplicity[i];
      EXPECT_EQ(all.film.pixelCounts()[i], n) << i;
      for (double v : {all.film.pixelSums()[i].r, all.film.pixelSums()[i].g})
        off = std::max(off, std::fabs(v / n - 0.5) / (0.5 / n));
    }
    return off;
  };
  EXPECT_LE(worst(PixelSampling::Points::Hammersley), 1 + 1e-4);
  EXPECT_GT(worst(PixelSampling::Points::Hashed), 3.0);
  // The default, Sobol points: 16 and 64 samples are (0, m, 2)-nets, so their mean is as close.
  EXPECT_LE(worst(PixelSampling::Points::Sobol), 1 + 1e-4);
  // Half of the samples: unbiased over the film (300 pixels x 8 samples, more in some, each uniform: the
  // mean of u0 has a standard error of at most 0.29 / sqrt(2400) = 0.006).
  sampling.points = PixelSampling::Points::Hammersley;
  const PartialResult half = runSampleUnit(eval, plan, plan.units.front(), nullptr, &sampling);
  double sum = 0, count = 0;
  for (size_t i = 0; i < half.film.pixelCount(); ++i) {
    sum += half.film.pixelSums()[i].r;
    count += half.film.pixelCounts()[i];
  }
  EXPECT_NEAR(sum / count, 0.5, 4 * 0.006);
  EXPECT_EQ(double(half.samples), count) << "the samples taken, multiplicities included";
  // A multiplicity per pixel or none.
  sampling.multiplicity.pop_back();
  EXPECT_THROW(runSampleUnit(eval, plan, plan.units.front(), nullptr, &sampling), std::invalid_argument);
}

// sobolPixelPoint: every prefix of 2^m points of a pixel is a (0, m, 2)-net (exactly one point in each of
// the 2^m boxes of 2^-a x 2^-(m-a), for every a), whatever the pixel's key: what a time budget stopping at
// any power of two gets. Without the net (hashed points) 16 points leave some of 16 boxes empty almost surely.
TEST(SobolPixelPoint, EveryPrefixOfTwoToTheMPointsIsANet) {
  for (uint64_t key : {uint64_t(1), uint64_t(0x9e3779b97f4a7c15ULL), hashKeys(7, 3)}) {
    for (int m = 0; m <= 10; ++m) {
      const uint32_t n = 1u << m;
      for (int a = 0; a <= m; ++a) {
        std::vector<int> boxes(n, 0);
        for (uint32_t k = 0; k < n; ++k) {
          const Vec2 u = sobolPixelPoint(key, k);
          ASSERT_TRUE(u.x >= 0 && u.x < 1 && u.y >= 0 && u.y < 1) << key << " " << k;
          const uint32_t bx = uint32_t(u.x * float(1u << a)), by = uint32_t(u.y * float(1u << (m - a)));
          ++boxes[(by << a) | bx];
        }
        for (uint32_t b = 0; b < n; ++b) ASSERT_EQ(boxes[b], 1) << "key " << key << " m " << m << " a " << a << " box " << b;
      }
    }
  }
}

// Each point on its own is uniform over the pixel (over keys): the random digital shift is what keeps a
// pixel's mean unbiased. Chi-square of 40000 keys' point k on an 8 x 8 grid (63 degrees of freedom; the
// 0.999 quantile is 103.4), for the first point and later ones. A shift by a fixed mask would put every
// key's point 0 in one cell (chi-square 2.5e6).
TEST(SobolPixelPoint, EachPointIsUniformOverKeys) {
  constexpr int kKeys = 40000, kCells = 64;
  for (uint32_t k : {0u, 1u, 5u, 1000u, 65535u}) {
    std::vector<double> cells(kCells, 0.0);
    for (int i = 0; i < kKeys; ++i) {
      const Vec2 u = sobolPixelPoint(hashKeys(11, uint64_t(i)), k);
      ++cells[size_t(int(u.y * 8) * 8 + int(u.x * 8))];
    }
    const double expected = double(kKeys) / kCells;
    double chi2 = 0;
    for (double c : cells) chi2 += (c - expected) * (c - expected) / expected;
    EXPECT_LT(chi2, 103.4) << "point " << k;
  }
}

TEST(JobApi, SplatsAreNormalizedByPixelsOverLightPaths) {
  // With lt every splat of the stand-in goes to the splat buffer, developed with scale P / N
  // (N = spp * P light paths). Blue channel:
  //  - the "camera" splat (blue 1) lands in its own pixel spp times: P / N * spp = 1 exactly per pixel;
  //  - the random splats (blue 1, K ~ Binomial(N, 1/2) of them anywhere) add K / N to the image mean:
  //    expectation 1/2, standard error sqrt(N / 4) / N.
  const int w = 16, h = 16, spp = 64;
  RenderSettings s = settingsFor("lt", spp, w, h);
  const JobPlan plan = planSampleJob(s);
  const FakeEvaluator eval(w, h, /*splatsOnly=*/true);
  PartialResult merged;
  for (const WorkUnit& u : plan.units) merged.add(runSampleUnit(eval, plan, u));
  for (size_t i = 0; i < merged.film.pixelCount(); ++i) EXPECT_EQ(merged.film.pixelCounts()[i], 0.0);
  const std::vector<Color> img = developSampleImage(plan, merged);
  double meanB = 0;
  for (const Color& c : img) meanB += c.b;
  meanB /= img.size();
  const double N = double(spp) * w * h;
  EXPECT_NEAR(meanB, 1.5, 5 * std::sqrt(N * 0.25) / N);
  // A pixel never receives less than its own camera splats.
  for (const Color& c : img) EXPECT_GE(c.b, 1.0f - 1e-6f);
}

TEST(JobApi, TechniqueImagesSumToTheFullImage) {
  // The stand-in's camera sample is technique (s, t) = (0, 2) and its random splat (1, 1): path length 1.
  const int w = 12, h = 10;
  RenderSettings s = settingsFor("bdpt", 5, w, h);
  const JobPlan plan = planSampleJob(s);
  const FakeEvaluator eval(w, h);
  TechniqueFilms techniques(1, w, h);
  ASSERT_EQ(techniques.films.size(), 2u);
  PartialResult merged;
  for (const WorkUnit& u : plan.units) merged.add(runSampleUnit(eval, plan, u, &techniques));
  const double scale = double(w * h) / double(merged.samples);
  const std::vector<Color> full = developSampleImage(plan, merged);
  const std::vector<Color> cam = techniques.films[TechniqueFilms::index(0, 2)].develop(scale);
  const std::vector<Color> light = techniques.films[TechniqueFilms::index(1, 1)].develop(scale);
  double lightTotal = 0;
  for (size_t i = 0; i < full.size(); ++i) {
    EXPECT_NEAR(cam[i].r + light[i].r, full[i].r, 1e-5f * (1 + full[i].r)) << i;
    EXPECT_NEAR(cam[i].b + light[i].b, full[i].b, 1e-5f * (1 + full[i].b)) << i;
    lightTotal += light[i].r;
  }
  EXPECT_GT(lightTotal, 0.0);
  // Running with technique films does not change the main result.
  PartialResult plain;
  for (const WorkUnit& u : plan.units) plain.add(runSampleUnit(eval, plan, u));
  expectBitIdentical(plain.film, merged.film);
}

// Values over many orders of magnitude (like fireflies next to dim pixels), so that double sums of
// unquantized units depend on the order of additions.
class WideRangeEvaluator final : public PathEvaluator {
 public:
  WideRangeEvaluator(int w, int h, bool splatsOnly = false) : w_(w), h_(h), splatsOnly_(splatsOnly) {}
  bool splatsOnly() const override { return splatsOnly_; }
  void evaluate(SampleSource& src, const Vec2* pixel, PathContribution& out) const override {
    src.startStream(Stream::Camera);
    const Vec2 u = src.next2D();
    const float v = std::exp2(-30.f * u.x) * (1.f + u.y) * 1000.f;
    out.cameraRaster = Vec2(pixel->x + u.x, pixel->y + u.y);
    out.splats.push_back({out.cameraRaster, Color(v, 1.f / (1.f + v), u.y), 0, 2});
    src.startStream(Stream::Light);
    const Vec2 p = src.next2D();
    out.splats.push_back({Vec2(p.x * w_, p.y * h_), Color(v * 0.37f, u.x, 3e-6f * v), 1, 1});
  }

 private:
  int w_, h_;
  bool splatsOnly_;
};

// Sample units merge exactly: any grouping of the same units (one by one, as `--in-process` does, or in
// contiguous tasks summed first, as the farm does) gives bit-identical sums, and those sums are
// multiples of 2^-kQuantumExp.
TEST(JobApi, AnyGroupingOfSampleUnitsGivesIdenticalBits) {
  const int w = 9, h = 7;
  for (std::string m : {"bdpt", "lt"}) {
    RenderSettings s = settingsFor(m, 12, w, h);
    s.samplesPerUnit = 1;
    const JobPlan plan = planSampleJob(s);
    ASSERT_EQ(plan.units.size(), 12u);
    const WideRangeEvaluator eval(w, h, /*splatsOnly=*/m == "lt");
    std::vector<PartialResult> units;
    for (const WorkUnit& u : plan.units) units.push_back(runSampleUnit(eval, plan, u));
    for (const PartialResult& r : units)
      for (size_t i = 0; i < r.film.pixelCount(); ++i)
        for (double v : {r.film.pixelSums()[i].r, r.film.splatSums()[i].g, r.film.splatSums()[i].b}) {
          const double scaled = std::ldexp(v, 26);
          ASSERT_EQ(scaled, std::floor(scaled)) << "not a multiple of 2^-26: " << v;
        }
    // Groupings: tasks as contiguous ranges, summed from zero, then added in task order.
    auto mergeGrouped = [&](const std::vector<size_t>& bounds) {
      PartialResult merged;
      for (size_t g = 0; g + 1 < bounds.size(); ++g) {
        PartialResult task;
        task.film = Film(w, h);
        for (size_t u = bounds[g]; u < bounds[g + 1]; ++u) task.add(units[u]);
        merged.add(task);
      }
      return merged;
    };
    PartialResult oneByOne;
    for (const PartialResult& r : units) oneByOne.add(r);
    for (const std::vector<size_t>& bounds : std::vector<std::vector<size_t>>{
             {0, 12}, {0, 6, 12}, {0, 1, 5, 11, 12}, {0, 3, 6, 9, 12}, {0, 7, 8, 12}}) {
      PartialResult grouped = mergeGrouped(bounds);
      expectBitIdentical(oneByOne.film, grouped.film);
      for (size_t i = 0; i < oneByOne.film.pixelCount(); ++i) {
        EXPECT_EQ(std::bit_cast<uint64_t>(oneByOne.film.pixelSums()[i].b), std::bit_cast<uint64_t>(grouped.film.pixelSums()[i].b));
        EXPECT_EQ(std::bit_cast<uint64_t>(oneByOne.film.splatSums()[i].g), std::bit_cast<uint64_t>(grouped.film.splatSums()[i].g));
        EXPECT_EQ(std::bit_cast<uint64_t>(oneByOne.film.splatSums()[i].b), std::bit_cast<uint64_t>(grouped.film.splatSums()[i].b));
      }
      EXPECT_EQ(oneByOne.samples, grouped.samples);
      const std::vector<Color> a = developSampleImage(plan, oneByOne), b = developSampleImage(plan, grouped);
      ASSERT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Color)), 0) << m.c_str();
    }
    // The pixel counts stay exact integers.
    for (double c : oneByOne.film.pixelCounts()) EXPECT_EQ(c, m == "lt" ? 0.0 : 12.0);
  }
}

// Beyond the exact-merging range (a unit's sum of 2^26 or more in one pixel) the value is already a
// multiple of the quantum: it is kept exactly and the unit succeeds (a firefly never fails a render).
class HugeEvaluator final : public PathEvaluator {
 public:
  void evaluate(SampleSource& src, const Vec2* pixel, PathContribution& out) const override {
    src.startStream(Stream::Camera);
    src.next2D();
    out.cameraRaster = Vec2(pixel->x + 0.5f, pixel->y + 0.5f);
    out.splats.push_back({out.cameraRaster, Color(0.5f, 1e8f, 0.5f), 0, 2});
  }
};

TEST(JobApi, SampleUnitBeyondTheExactMergingRangeKeepsTheValue) {
  RenderSettings s = settingsFor("pt", 1, 4, 4);
  const JobPlan plan = planSampleJob(s);
  const HugeEvaluator eval;
  const PartialResult r = runSampleUnit(eval, plan, plan.units[0]);
  const double spp = plan.units[0].sampleEnd - plan.units[0].sampleBegin;
  for (const RGBd& v : r.film.pixelSums()) {
    EXPECT_EQ(v.g, spp * double(1e8f));                 // kept exactly
    EXPECT_EQ(std::ldexp(v.r, kQuantumExp), std::floor(std::ldexp(v.r, kQuantumExp)));  // small ones quantized
  }
}

}  // namespace
}  // namespace mlt
