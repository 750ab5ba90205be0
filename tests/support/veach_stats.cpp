#include "tests/support/veach_stats.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "common/methods/veach/veach_job.h"

namespace mlt::test {

std::vector<double> tileMeans(const std::vector<Color>& img, int w, int h, int tiles) {
  if (w % tiles || h % tiles) throw std::invalid_argument("tileMeans: the film size must be a multiple of the tiles");
  std::vector<double> v(1 + tiles * tiles, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double L = luminance(img[size_t(y) * w + x]);
      v[0] += L / (w * h);
      v[1 + (y * tiles / h) * tiles + x * tiles / w] += L * tiles * tiles / (w * h);
    }
  return v;
}

ImageStats statsOverRuns(const std::vector<std::vector<double>>& values, int tiles) {
  ImageStats st;
  st.tilesX = st.tilesY = tiles;
  const size_t runs = values.size();
  st.n = runs;
  const size_t K = values[0].size();
  st.mean.assign(K, 0);
  st.stdErr.assign(K, 0);
  for (size_t k = 0; k < K; ++k) {
    double m = 0, sq = 0;
    for (const auto& v : values) m += v[k];
    m /= double(runs);
    for (const auto& v : values) sq += (v[k] - m) * (v[k] - m);
    st.mean[k] = m;
    st.stdErr[k] = std::sqrt(sq / double(runs - 1) / double(runs));
  }
  return st;
}

ImageStats veachStats(const RenderScene& scene, RenderSettings s, const veach::MutationSettings& mut, int runs,
                      int tiles, uint64_t seed0, std::string* acceptance) {
  std::vector<std::vector<double>> values;
  ChainStats all;
  for (int r = 0; r < runs; ++r) {
    s.seed = seed0 + uint64_t(r);
    const JobPlan plan = veach::planVeachJob(scene, s);
    std::vector<PartialResult> parts(plan.units.size());
    tbb::parallel_for(size_t(0), parts.size(),
                      [&](size_t i) { parts[i] = veach::runVeachChain(scene, plan, plan.units[i], mut); });
    PartialResult merged;
    for (const PartialResult& p : parts) merged.add(p);
    all.add(merged.stats);
    values.push_back(tileMeans(veach::developVeachImage(plan, merged, mut), s.width, s.height, tiles));
  }
  if (acceptance) *acceptance = veach::acceptanceSummary(all);
  return statsOverRuns(values, tiles);
}

}  // namespace mlt::test
