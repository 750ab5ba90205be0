#include "tests/support/estimates.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include "common/core/color.h"

namespace mlt::test {

ImageStats estimateImageFrom(const std::function<void(uint64_t, PathContribution&)>& sample, int width, int height,
                             uint64_t n, int tilesX, int tilesY, int channel, uint64_t batch) {
  const int K = 1 + tilesX * tilesY;
  if (batch == 0) batch = 512;
  const uint64_t nBatches = std::max<uint64_t>(2, (n + batch - 1) / batch);
  std::vector<std::vector<double>> batchMean(nBatches, std::vector<double>(K, 0.0));
  // Fixed batches, combined in batch order: the result does not depend on the thread count.
  tbb::parallel_for(uint64_t(0), nBatches, [&](uint64_t b) {
    PathContribution c;
    std::vector<double>& v = batchMean[b];
    for (uint64_t i = b * batch; i < (b + 1) * batch; ++i) {
      c.clear();
      sample(i, c);
      for (const Splat& s : c.splats) {
        const double x = channel < 0 ? luminance(s.L) : s.L[channel];
        if (!(s.pRaster.x >= 0 && s.pRaster.x < width && s.pRaster.y >= 0 && s.pRaster.y < height)) continue;
        const int tx = std::min(tilesX - 1, int(s.pRaster.x * tilesX / width));
        const int ty = std::min(tilesY - 1, int(s.pRaster.y * tilesY / height));
        v[0] += x;
        v[1 + ty * tilesX + tx] += x * (tilesX * tilesY);
      }
    }
    for (double& x : v) x /= double(batch);
  });
  ImageStats st;
  st.tilesX = tilesX;
  st.tilesY = tilesY;
  st.n = nBatches * batch;
  st.mean.assign(K, 0.0);
  st.stdErr.assign(K, 0.0);
  for (int k = 0; k < K; ++k) {
    double s = 0, s2 = 0;
    for (uint64_t b = 0; b < nBatches; ++b) {
      s += batchMean[b][k];
      s2 += batchMean[b][k] * batchMean[b][k];
    }
    const double m = s / double(nBatches);
    const double var = std::max(0.0, (s2 / double(nBatches) - m * m)) * double(nBatches) / double(nBatches - 1);
    st.mean[k] = m;
    st.stdErr[k] = std::sqrt(var / double(nBatches));
  }
  return st;
}

ImageStats estimateImage(const PathEvaluator& evaluator, int width, int height, uint64_t seed, uint64_t n,
                         int tilesX, int tilesY, int channel, const std::function<bool(const Splat&)>& filter) {
  const uint64_t P = uint64_t(width) * uint64_t(height);
  return estimateImageFrom(
      [&](uint64_t i, PathContribution& c) {
        IndependentSource source(seed, i);
        const uint64_t pix = i % P;
        const Vec2 pixel{float(pix % uint64_t(width)), float(pix / uint64_t(width))};
        evaluator.evaluate(source, &pixel, c);
        if (filter) {
          size_t k = 0;
          for (const Splat& s : c.splats)
            if (filter(s)) c.splats[k++] = s;
          c.splats.resize(k);
        }
      },
      width, height, n, tilesX, tilesY, channel, P);
}

double maxZ(const ImageStats& a, const ImageStats& b, int* where) {
  double worst = 0;
  for (int k = 0; k < a.size() && k < b.size(); ++k) {
    const double se = std::sqrt(a.stdErr[k] * a.stdErr[k] + b.stdErr[k] * b.stdErr[k]);
    const double d = std::fabs(a.mean[k] - b.mean[k]);
    const double z = se > 0 ? d / se : (d > 0 ? INFINITY : 0.0);
    if (z > worst) {
      worst = z;
      if (where) *where = k;
    }
  }
  return worst;
}

double zImage(const ImageStats& a, double value) {
  const double d = std::fabs(a.mean[0] - value);
  return a.stdErr[0] > 0 ? d / a.stdErr[0] : (d > 0 ? INFINITY : 0.0);
}

}  // namespace mlt::test
