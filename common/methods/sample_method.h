// The family of methods that render batches of independent pixel samples through one path evaluator
// (pt, lt, bdpt). A method of this family supplies its evaluator; planning (sample batches), running a
// unit, developing (pixel means and splats scaled by P / N) and the metadata are shared
// (common/job/sample_job.h).
#pragma once
#include <memory>

#include "common/integrators/path_evaluator.h"
#include "common/methods/method.h"

namespace mlt {

class SampleMethod : public RenderMethod {
 public:
  MethodFamily family() const final { return MethodFamily::Samples; }
  virtual std::unique_ptr<PathEvaluator> makeEvaluator(const RenderScene& scene, const RenderSettings& settings) const = 0;

  void validate(const RenderSettings& settings) const override;
  JobPlan plan(const RenderScene& scene, const RenderSettings& settings) const override;
  PartialResult runUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) const override;
  std::vector<Color> develop(const JobPlan& plan, const PartialResult& merged) const override;
  void addMetadata(const JobPlan& plan, const PartialResult& merged, ImageMetadata& metadata) const override;
};

}  // namespace mlt
