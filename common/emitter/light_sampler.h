// Light selection for next-event estimation and light subpaths: a light picked in proportion to its power.
#pragma once
#include <cstddef>
#include <optional>
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
  // Inverse of sample() (reversible-jump MLT): the u with which sample() picks lightIndex, placed in the
  // light's interval [cdf_i, cdf_i+1) at gamma (eq. 40 of Bitterli et al. 2017); its Jacobian is the
  // interval's width, pmf(lightIndex). nullopt for an invalid index or a light that is never picked.
  std::optional<float> invertSample(int lightIndex, float gamma) const;
  size_t size() const { return pmf_.size(); }

 private:
  std::vector<float> pmf_, cdf_;
};

}  // namespace mlt
