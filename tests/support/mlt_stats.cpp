#include "tests/support/mlt_stats.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace mlt::test {

ImageStats markovChainStats(const RenderScene& scene, RenderSettings s, int w, int h, int runs, int tiles,
                            uint64_t seed0) {
  if (w % tiles || h % tiles)
    throw std::invalid_argument("markovChainStats: the film size must be a multiple of the tile count");
  std::vector<std::vector<double>> values;
  for (int r = 0; r < runs; ++r) {
    s.seed = seed0 + r;
    const JobPlan plan = planJob(scene, s);
    std::vector<PartialResult> parts(plan.units.size());
    tbb::parallel_for(size_t(0), parts.size(), [&](size_t i) { parts[i] = runWorkUnit(scene, plan, plan.units[i]); });
    PartialResult merged;
    for (const PartialResult& p : parts) merged.add(p);
    const std::vector<Color> img = developImage(plan, merged);
    std::vector<double> v(1 + tiles * tiles, 0.0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double L = luminance(img[size_t(y) * w + x]);
        v[0] += L / (w * h);
        v[1 + (y * tiles / h) * tiles + x * tiles / w] += L * tiles * tiles / (w * h);
      }
    values.push_back(v);
  }
  ImageStats st;
  st.tilesX = st.tilesY = tiles;
  st.n = uint64_t(runs);
  const size_t K = values[0].size();
  st.mean.assign(K, 0);
  st.stdErr.assign(K, 0);
  for (size_t k = 0; k < K; ++k) {
    double m = 0, sq = 0;
    for (const auto& v : values) m += v[k];
    m /= runs;
    for (const auto& v : values) sq += (v[k] - m) * (v[k] - m);
    st.mean[k] = m;
    st.stdErr[k] = std::sqrt(sq / (runs - 1) / runs);
  }
  return st;
}

}  // namespace mlt::test
