#include "common/methods/bdpt/bdpt_method.h"

#include "common/integrators/evaluators.h"

namespace mlt {

std::unique_ptr<PathEvaluator> BdptMethod::makeEvaluator(const RenderScene& scene, const RenderSettings& settings) const {
  return mlt::makeEvaluator(scene, "bdpt", settings.integrator);
}

}  // namespace mlt
