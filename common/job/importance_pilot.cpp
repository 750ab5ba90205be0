#include "common/job/importance_pilot.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/core/rng.h"
#include "common/integrators/evaluators.h"
#include "common/mlt/bootstrap.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"

namespace mlt {

namespace {
constexpr uint64_t kImportanceKey = 0x696d7070ULL;  // "impp"
}  // namespace

ImportancePilot importancePilot(const RenderScene& scene, const RenderSettings& s, double floor, bool parallel) {
  const auto t0 = std::chrono::steady_clock::now();
  const int W = s.width, H = s.height;
  const ImportanceMap grid = importanceGrid(W, H);
  const int T = grid.tileSize, X = grid.tilesX, Y = grid.tilesY;
  const std::unique_ptr<PathEvaluator> pt = makeEvaluator(scene, "pt", s.integrator);
  // Samples per pixel: at least kImportancePooledSamples behind each tile's g (3 x 3 tiles of T x T pixels).
  const uint32_t spp = uint32_t((kImportancePooledSamples + 9 * T * T - 1) / (9 * T * T));
  // Per tile row: the tiles' sums of luminance and the numbers drawn, reduced in row order (deterministic
  // whatever the threads do).
  std::vector<double> sums(size_t(X) * size_t(Y), 0.0);
  std::vector<uint64_t> reads(size_t(Y), 0);
  const auto tileRows = [&](const tbb::blocked_range<int>& r) {
    PathContribution path;
    IndependentSource source(0, 0);
    for (int ty = r.begin(); ty != r.end(); ++ty) {
      uint64_t drawn = 0;
      for (int y = ty * T; y < std::min(H, (ty + 1) * T); ++y)
        for (int x = 0; x < W; ++x) {
          for (uint32_t i = 0; i < spp; ++i) {
            source.reset(hashKeys(s.seed, kImportanceKey, i), uint64_t(y) * uint64_t(W) + uint64_t(x));
            const uint32_t before = source.reads();
            path.clear();
            const Vec2 pixel{float(x), float(y)};
            pt->evaluate(source, &pixel, path);
            drawn += source.reads() - before;
            const double v = luminance(path.total());
            if (!(std::isfinite(v) && v >= 0))
              throw std::runtime_error("importance pilot: the pt sample of pixel (" + std::to_string(x) + ", " +
                                       std::to_string(y) + ") is " + std::to_string(v));
            sums[size_t(ty) * size_t(X) + size_t(x / T)] += v;
          }
        }
      reads[size_t(ty)] = drawn;
    }
  };
  if (parallel) tbb::parallel_for(tbb::blocked_range<int>(0, Y, 1), tileRows);
  else tileRows(tbb::blocked_range<int>(0, Y));

  std::vector<uint64_t> counts(sums.size());
  for (int ty = 0; ty < Y; ++ty)
    for (int tx = 0; tx < X; ++tx) {
      const uint64_t w = uint64_t(std::min(W, (tx + 1) * T) - tx * T), h = uint64_t(std::min(H, (ty + 1) * T) - ty * T);
      counts[size_t(ty) * size_t(X) + size_t(tx)] = w * h * spp;
    }
  ImportancePilot out;
  out.map = importanceFromTileSums(W, H, sums, counts, floor);
  out.floor = floor;
  out.samples = uint64_t(W) * uint64_t(H) * spp;
  uint64_t drawn = 0;
  for (uint64_t r : reads) drawn += r;
  out.cost = double(drawn) + kCandidateOverhead * double(out.samples);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace mlt
