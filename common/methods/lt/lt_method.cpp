#include "common/methods/lt/lt_method.h"

#include "common/integrators/evaluators.h"

namespace mlt {

std::unique_ptr<PathEvaluator> LtMethod::makeEvaluator(const RenderScene& scene, const RenderSettings& settings) const {
  return mlt::makeEvaluator(scene, "lt", settings.integrator);
}

}  // namespace mlt
