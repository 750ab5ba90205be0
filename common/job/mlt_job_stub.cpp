// TEMPORARY weak stubs for the Markov-chain job API until common/job/mlt_job.cpp exists (see mlt_job.h).
// Delete this file once the real implementation is committed.
#include <stdexcept>

#include "common/job/mlt_job.h"

namespace mlt {

[[gnu::weak]] JobPlan planMarkovChainJob(const RenderScene&, const RenderSettings& settings) {
  throw std::runtime_error(std::string("method '") + methodName(settings.method) + "' is not implemented yet");
}
[[gnu::weak]] PartialResult runMarkovChain(const RenderScene&, const JobPlan& plan, const WorkUnit&) {
  throw std::runtime_error(std::string("method '") + methodName(plan.settings.method) + "' is not implemented yet");
}
[[gnu::weak]] std::vector<Color> developMarkovChainImage(const JobPlan& plan, const PartialResult&) {
  throw std::runtime_error(std::string("method '") + methodName(plan.settings.method) + "' is not implemented yet");
}

}  // namespace mlt
