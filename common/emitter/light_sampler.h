// Light selection for next-event estimation and light subpaths: a light picked in proportion to its power.
#pragma once
#include <cstddef>
#include <vector>

#include "common/interfaces/light.h"

namespace mlt {

// Picks a light in proportion to its power (alias-free: a CDF over lights; a handful of lights).
class LightSampler {
 public:
  explicit LightSampler(const std::vector<const Light*>& lights);
  // Consumes 1 number. Returns the light index and its probability; -1 if there are no lights.
  int sample(float u, float* pmf) const;
  float pmf(int lightIndex) const;
  size_t size() const { return pmf_.size(); }

 private:
  std::vector<float> pmf_, cdf_;
};

}  // namespace mlt
