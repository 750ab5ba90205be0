// LightSampler: a light chosen in proportion to its power.
#include "common/emitter/light_sampler.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/core/sampling_inverse.h"

namespace mlt {

// pmf_i = luminance(Phi_i) / sum_j luminance(Phi_j); uniform if every light has zero power.
LightSampler::LightSampler(const std::vector<const Light*>& lights) {
  const size_t n = lights.size();
  pmf_.assign(n, 0.0f);
  cdf_.assign(n + 1, 0.0f);
  double total = 0;
  std::vector<double> w(n);
  for (size_t i = 0; i < n; ++i) {
    w[i] = luminance(lights[i]->power());
    if (!std::isfinite(w[i]) || w[i] < 0)
      throw std::runtime_error("light " + std::to_string(i) + ": power is negative or not finite");
    total += w[i];
  }
  if (!(total > 0)) {
    std::fill(w.begin(), w.end(), 1.0);
    total = double(n);
  }
  double acc = 0;
  for (size_t i = 0; i < n; ++i) {
    pmf_[i] = static_cast<float>(w[i] / total);
    acc += w[i];
    cdf_[i + 1] = static_cast<float>(acc / total);
  }
  if (n > 0) cdf_[n] = 1.0f;
}

int LightSampler::sample(float u, float* pmf) const {
  const size_t n = pmf_.size();
  if (n == 0) {
    if (pmf) *pmf = 0;
    return -1;
  }
  size_t i = std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin();
  i = std::clamp<size_t>(i, 1, n) - 1;
  while (pmf_[i] == 0 && i + 1 < n) ++i;  // guard against rounding landing on an empty interval
  if (pmf) *pmf = pmf_[i];
  return static_cast<int>(i);
}

float LightSampler::pmf(int lightIndex) const {
  return lightIndex >= 0 && size_t(lightIndex) < pmf_.size() ? pmf_[lightIndex] : 0.0f;
}

std::optional<float> LightSampler::invertSample(int lightIndex, float gamma) const {
  if (lightIndex < 0 || size_t(lightIndex) >= pmf_.size() || !(pmf_[lightIndex] > 0)) return std::nullopt;
  const float u = invertInterval(cdf_[lightIndex], cdf_[lightIndex + 1], gamma);
  float pmf = 0;
  if (sample(u, &pmf) != lightIndex) return std::nullopt;  // an interval lost to float rounding
  return u;
}

}  // namespace mlt
