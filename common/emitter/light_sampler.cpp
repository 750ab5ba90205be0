// makeLight (dispatch on LightDesc::Type) and LightSampler (choice by power).
#include <algorithm>
#include <stdexcept>
#include <string>

#include "common/emitter/light_factories.h"
#include "common/scene/scene_desc.h"

namespace mlt {

std::unique_ptr<Light> makeLight(const LightDesc& desc) {
  const Color& I = desc.intensity;
  if (!I.isFinite() || I.r < 0 || I.g < 0 || I.b < 0)
    throw std::runtime_error("light: intensity/irradiance/radiance must be finite and non-negative");
  if (!isFinite(desc.position)) throw std::runtime_error("light: position is not finite");
  if (!isFinite(desc.direction)) throw std::runtime_error("light: direction is not finite");
  switch (desc.type) {
    case LightDesc::Type::Point: return makePointLight(desc.position, I);
    case LightDesc::Type::Spot:
      return makeSpotLight(desc.position, desc.direction, I, desc.cutoffAngleDeg, desc.beamWidthDeg);
    case LightDesc::Type::Directional: return makeDirectionalLight(desc.direction, I);
    case LightDesc::Type::Constant: return makeConstantEnvironment(I);
  }
  throw std::runtime_error("light: unknown type " + std::to_string(static_cast<int>(desc.type)));
}

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

}  // namespace mlt
