#include "common/methods/pt/pt_method.h"

#include "common/integrators/evaluators.h"

namespace mlt {

std::unique_ptr<PathEvaluator> PtMethod::makeEvaluator(const RenderScene& scene, const RenderSettings& settings) const {
  return mlt::makeEvaluator(scene, "pt", settings.integrator);
}

}  // namespace mlt
