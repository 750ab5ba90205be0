// The method "lt": light tracing: light subpaths connected to the camera (common/integrators/evaluators.h), as batches of pixel samples.
#pragma once
#include "common/methods/sample_method.h"

namespace mlt {

class LtMethod final : public SampleMethod {
 public:
  std::string name() const override { return "lt"; }
  std::string description() const override { return "light tracing: light subpaths connected to the camera"; }
  std::unique_ptr<PathEvaluator> makeEvaluator(const RenderScene& scene, const RenderSettings& settings) const override;
};

}  // namespace mlt
