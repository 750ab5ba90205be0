// The method "bdpt": bidirectional path tracing, every strategy MIS-weighted (common/integrators/evaluators.h), as batches of pixel samples.
#pragma once
#include "common/methods/sample_method.h"

namespace mlt {

class BdptMethod final : public SampleMethod {
 public:
  std::string name() const override { return "bdpt"; }
  std::string description() const override { return "bidirectional path tracing, every strategy MIS-weighted"; }
  std::unique_ptr<PathEvaluator> makeEvaluator(const RenderScene& scene, const RenderSettings& settings) const override;
};

}  // namespace mlt
