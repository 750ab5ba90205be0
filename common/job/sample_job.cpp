// pt, lt and bdpt as work units of independent pixel samples (see sample_job.h for the sample indexing).
//
// Bit-identical sums whatever the thread count: the film receives its additions in one fixed order,
//   tile group g (ascending) -> sample k (ascending) -> tile (ascending) -> pixel (row-major) -> splat,
// which is the order a single thread would use. Tiles are evaluated in parallel; pixel estimates go
// straight to their pixel (each pixel belongs to exactly one tile, so no two threads touch one entry),
// while splats, which can land anywhere, are buffered per tile and added sequentially afterwards.
// Tile groups bound the splat buffers' memory; the group size depends on the image only.
#include "common/job/sample_job.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

#include "common/core/rng.h"
#include "common/mlt/develop.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"

namespace mlt {

namespace {

constexpr int kTileSize = 16;
constexpr int kTilesPerGroup = 64;

struct TileOutput {
  struct PendingSplat {
    Vec2 pRaster;
    Color L;
  };
  std::vector<PendingSplat> splats;
  std::vector<std::pair<int, PendingSplat>> techniqueSplats;  // (technique index, splat)
  uint64_t nonFinite = 0;
};

}  // namespace

JobPlan planSampleJob(const RenderSettings& settings) {
  if (settings.spp < 1) throw std::invalid_argument("settings: spp must be >= 1, got " + std::to_string(settings.spp));
  if (settings.samplesPerUnit < 0)
    throw std::invalid_argument("settings: samples per unit must be >= 0, got " + std::to_string(settings.samplesPerUnit));
  if (settings.width <= 0 || settings.height <= 0) throw std::invalid_argument("settings: film size not resolved");
  JobPlan plan;
  plan.settings = settings;
  int perUnit = settings.samplesPerUnit;
  if (perUnit == 0) perUnit = (settings.spp + kAutoSampleUnits - 1) / kAutoSampleUnits;
  perUnit = std::min(perUnit, settings.spp);
  plan.settings.samplesPerUnit = perUnit;
  uint32_t index = 0;
  for (int begin = 0; begin < settings.spp; begin += perUnit) {
    WorkUnit u;
    u.index = index++;
    u.sampleBegin = uint32_t(begin);
    u.sampleEnd = uint32_t(std::min(settings.spp, begin + perUnit));
    plan.units.push_back(u);
  }
  return plan;
}

TechniqueFilms::TechniqueFilms(int maxLength_, int width, int height) : maxLength(maxLength_) {
  if (maxLength < 1) throw std::invalid_argument("technique films: maximum path length must be >= 1");
  films.assign(size_t(count(maxLength)), Film(width, height));
}

PartialResult runSampleUnit(const PathEvaluator& evaluator, const JobPlan& plan, const WorkUnit& unit) {
  return runSampleUnit(evaluator, plan, unit, nullptr);
}

PartialResult runSampleUnit(const PathEvaluator& evaluator, const JobPlan& plan, const WorkUnit& unit,
                            TechniqueFilms* techniques, const PixelSampling* sampling) {
  const auto start = std::chrono::steady_clock::now();
  const RenderSettings& s = plan.settings;
  if (unit.sampleEnd <= unit.sampleBegin || unit.sampleEnd > uint32_t(s.spp))
    throw std::invalid_argument("work unit " + std::to_string(unit.index) + ": sample range [" +
                                std::to_string(unit.sampleBegin) + ", " + std::to_string(unit.sampleEnd) +
                                ") is empty or beyond spp " + std::to_string(s.spp));
  const int width = s.width, height = s.height;
  if (sampling && !sampling->multiplicity.empty() && sampling->multiplicity.size() != size_t(width) * size_t(height))
    throw std::invalid_argument("sample unit: pixel multiplicities for " + std::to_string(sampling->multiplicity.size()) +
                                " pixels on a " + std::to_string(width) + "x" + std::to_string(height) + " film");
  const bool lightTracing = evaluator.splatsOnly();  // lt: every splat goes to the splat sums
  const PixelSampling::Points points = sampling ? sampling->points : PixelSampling::Points::Sobol;
  PartialResult result;
  result.film = Film(width, height);
  result.units = {unit.index};
  Film& film = result.film;

  const int tilesX = (width + kTileSize - 1) / kTileSize, tilesY = (height + kTileSize - 1) / kTileSize;
  const int nTiles = tilesX * tilesY;
  std::vector<TileOutput> outputs(std::min(nTiles, kTilesPerGroup));

  for (int groupBegin = 0; groupBegin < nTiles; groupBegin += kTilesPerGroup) {
    const int groupEnd = std::min(nTiles, groupBegin + kTilesPerGroup);
    for (uint32_t k = unit.sampleBegin; k < unit.sampleEnd; ++k) {
      tbb::parallel_for(groupBegin, groupEnd, [&](int tile) {
        TileOutput& out = outputs[tile - groupBegin];
        out.splats.clear();
        out.nonFinite = 0;
        const int x0 = (tile % tilesX) * kTileSize, y0 = (tile / tilesX) * kTileSize;
        const int x1 = std::min(width, x0 + kTileSize), y1 = std::min(height, y0 + kTileSize);
        PathContribution contribution;
        IndependentSource source(0, 0);
        out.techniqueSplats.clear();
        std::vector<Color> techniqueL(techniques ? techniques->films.size() : 0);
        for (int y = y0; y < y1; ++y) {
          for (int x = x0; x < x1; ++x) {
            const uint64_t pixelIndex = uint64_t(y) * uint64_t(width) + uint64_t(x);
            const uint64_t key = hashKeys(s.seed, pixelIndex);
            const uint32_t m = sampling && !sampling->multiplicity.empty()
                                   ? std::max<uint32_t>(1, sampling->multiplicity[pixelIndex]) : 1;
            for (uint32_t r = 0; r < m; ++r) {
              const uint64_t i = uint64_t(k) * m + r;  // m = 1: i = k, the sample as it always was
              source.reset(key, i);
              if (!lightTracing && points == PixelSampling::Points::Sobol)
                source.setPixelPoint(sobolPixelPoint(key, uint32_t(i)));
              else if (!lightTracing && points == PixelSampling::Points::Hammersley)
                source.setPixelPoint(stratifiedPixelPoint(key, uint32_t(i), uint32_t(s.spp) * m));
              const Vec2 pixel{float(x), float(y)};
              contribution.clear();
              evaluator.evaluate(source, &pixel, contribution);
              Color L;  // the camera sample: every t >= 2 (or pt's t < 0) strategy, summed
              for (const Splat& sp : contribution.splats) {
                if (lightTracing || sp.t == 1) out.splats.push_back({sp.pRaster, sp.L});
                else L += sp.L;
              }
              if (techniques) {
                std::fill(techniqueL.begin(), techniqueL.end(), Color());
                for (const Splat& sp : contribution.splats) {
                  if (sp.s < 0 || sp.t < 1 || sp.s + sp.t - 1 > techniques->maxLength || !sp.L.isFinite()) continue;
                  const int ti = TechniqueFilms::index(sp.s, sp.t);
                  if (sp.t == 1) out.techniqueSplats.push_back({ti, {sp.pRaster, sp.L}});
                  else techniqueL[ti] += sp.L;
                }
                if (!lightTracing)
                  for (size_t ti = 0; ti < techniqueL.size(); ++ti)
                    techniques->films[ti].addSample(Vec2(float(x) + 0.5f, float(y) + 0.5f), techniqueL[ti]);
              }
              if (lightTracing) continue;
              if (!L.isFinite()) {
                ++out.nonFinite;
                continue;
              }
              // Binned at the pixel centre: the sample belongs to pixel (x, y) by construction, even when
              // x + u rounds up to x + 1 in float. Only this tile's thread writes this pixel's entries.
              film.addSample(Vec2(float(x) + 0.5f, float(y) + 0.5f), L);
            }
          }
        }
      });
      for (int tile = groupBegin; tile < groupEnd; ++tile) {
        const TileOutput& out = outputs[tile - groupBegin];
        for (const auto& sp : out.splats) film.addSplat(sp.pRaster, sp.L);
        if (techniques)
          for (const auto& [ti, sp] : out.techniqueSplats) techniques->films[ti].addSplat(sp.pRaster, sp.L);
        film.setNonFiniteSamples(film.nonFiniteSamples() + out.nonFinite);
      }
    }
  }
  // Exact merging in any grouping (common/mlt/develop.h): sums become multiples of 2^-kQuantumExp, so
  // adding units one by one (in-process) or task by task (the farm) gives the same bits. Pixel counts
  // are small integers and already exact. The technique films are never merged across processes.
  quantizeFilm(film, s.seed, unit.index);
  // Camera samples taken (light paths, for lt's P / N): the sample indices times each pixel's multiplicity.
  uint64_t perIndex = film.pixelCount();
  if (sampling && !sampling->multiplicity.empty()) {
    perIndex = 0;
    for (uint8_t m : sampling->multiplicity) perIndex += std::max<uint32_t>(1, m);
  }
  result.samples = uint64_t(unit.sampleEnd - unit.sampleBegin) * perIndex;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

// Development (normalization in one place).
//  Pixel estimates (pt; bdpt t >= 2): the box-filtered mean, pixelSum / pixelCount.
//  Splats (lt; bdpt t = 1): the camera importance We is normalized over the whole film (camera.h), so a
//  path splatted at raster position r estimates the film-wide measurement with weight 1 / N, where N is
//  the number of light paths traced. Pixel j's importance is P * We restricted to pixel j (P = pixel
//  count), hence
//      I_j = (1 / N) * sum_{splats in j} P * L = (P / N) * splatSum_j,   N = (samples per pixel) * P.
//  N is read from the merged result (samples = pixel samples it holds = light paths), not from the plan,
//  so a time-limited render that ran only some units develops correctly.
std::vector<Color> developSampleImage(const JobPlan& plan, const PartialResult& merged) {
  if (merged.film.pixelCount() == 0) throw std::invalid_argument("developImage: no work units merged");
  const double P = double(merged.film.pixelCount());
  const double N = double(merged.samples);
  return merged.film.develop(N > 0 ? P / N : 0.0);
}

}  // namespace mlt
