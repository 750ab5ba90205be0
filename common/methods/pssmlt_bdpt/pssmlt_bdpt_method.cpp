#include "common/methods/pssmlt_bdpt/pssmlt_bdpt_method.h"

#include "common/integrators/evaluators.h"

namespace mlt {

std::unique_ptr<PssTarget> PssmltBdptMethod::makeTarget(const RenderScene& scene, const RenderSettings& settings) const {
  return std::make_unique<EvaluatorPssTarget>(makeEvaluator(scene, "bdpt", settings.integrator), directPassSegments(settings));
}

}  // namespace mlt
