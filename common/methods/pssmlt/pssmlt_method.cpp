#include "common/methods/pssmlt/pssmlt_method.h"

#include "common/integrators/evaluators.h"

namespace mlt {

std::unique_ptr<PssTarget> PssmltMethod::makeTarget(const RenderScene& scene, const RenderSettings& settings) const {
  return std::make_unique<EvaluatorPssTarget>(makeEvaluator(scene, "pt", settings.integrator), directPassSegments(settings));
}

}  // namespace mlt
