// The method "pt": path tracing with next-event estimation and MIS (common/integrators/evaluators.h), as batches of pixel samples.
#pragma once
#include "common/methods/sample_method.h"

namespace mlt {

class PtMethod final : public SampleMethod {
 public:
  std::string name() const override { return "pt"; }
  std::string description() const override { return "path tracing with next-event estimation and MIS"; }
  std::unique_ptr<PathEvaluator> makeEvaluator(const RenderScene& scene, const RenderSettings& settings) const override;
};

}  // namespace mlt
