#include "common/mlt/allocation.h"

#include <algorithm>
#include <cmath>

namespace mlt {

uint32_t allocationBin(Vec2 pRaster, int width, int height) {
  const int n = kAllocationBinsPerAxis;
  const int x = std::clamp(int(std::floor(double(pRaster.x) * n / std::max(width, 1))), 0, n - 1);
  const int y = std::clamp(int(std::floor(double(pRaster.y) * n / std::max(height, 1))), 0, n - 1);
  return uint32_t(y * n + x);
}

std::vector<double> allocationWeights(const std::vector<LengthBootstrap>& lengths) {
  std::vector<double> w;
  if (lengths.size() < 2) return w;
  for (const LengthBootstrap& lb : lengths)
    if (lb.bin.size() != lb.c.size()) return w;  // not binned: the plain rule
  // Bin image: mean luminance of bin t = (bins) * sum_k mean_i(c_i [bin(i) = t]) (each bin is 1/bins of
  // the film; E_u[c_k 1_t] = (1/P) sum_(j in t) I_kj).
  const size_t bins = size_t(kAllocationBinsPerAxis) * kAllocationBinsPerAxis;
  std::vector<double> image(bins, 0.0);
  for (const LengthBootstrap& lb : lengths) {
    if (lb.c.empty()) continue;
    const double scale = double(bins) / double(lb.c.size());
    for (size_t i = 0; i < lb.c.size(); ++i)
      if (lb.bin[i] < bins) image[lb.bin[i]] += lb.c[i] * scale;
  }
  for (const LengthBootstrap& lb : lengths) {
    double sumC = 0, sumCg = 0;  // in index order: deterministic
    for (size_t i = 0; i < lb.c.size(); ++i)
      if (lb.c[i] > 0 && lb.bin[i] < bins) {
        sumC += lb.c[i];
        sumCg += lb.c[i] / (image[lb.bin[i]] * image[lb.bin[i]] + kAllocationEps);
      }
    w.push_back(sumC > 0 ? lb.estimate.b * std::sqrt(sumCg / sumC) : 0.0);
  }
  return w;
}

std::vector<double> mutationWeights(const std::vector<LengthBootstrap>& lengths) {
  std::vector<double> w = allocationWeights(lengths);
  if (w.empty())
    for (const LengthBootstrap& lb : lengths) w.push_back(lb.estimate.b);
  return w;
}

}  // namespace mlt
