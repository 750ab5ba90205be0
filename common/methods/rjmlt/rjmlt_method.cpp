#include "common/methods/rjmlt/rjmlt_method.h"

#include <fmt/format.h>

#include <stdexcept>
#include <string>

#include "common/methods/mmlt/mmlt_method.h"
#include "common/methods/rjmlt/rjmlt_chain.h"
#include "common/render/render_scene.h"

namespace mlt {

RjmltTarget::RjmltTarget(const RenderScene& scene, const IntegratorSettings& integrator)
    : scene_(scene), integrator_(integrator) {
  const int k = integrator.maxDepth < 0 ? kUnlimitedVertices : integrator.maxDepth;
  ws_.reserve(k + 2, k + 1);
}

void RjmltTarget::evaluate(SampleSource& source, int pathLength, PathContribution& out) {
  if (state_) {
    state_->evaluate(out);
    return;
  }
  // MMLT's target (mmlt_method.h), keeping the path: technique from Connect[kConnectTechniqueDim].
  out.clear();
  const int k = pathLength;
  if (k < 1) throw std::invalid_argument("rjmlt: path length " + std::to_string(k) + " must be >= 1");
  const int s = mmltTechniqueOf(source, k);
  lastValid_ = traceTechnique(scene_, source, s, k + 1 - s, integrator_.heuristic, ws_, &last_);
  if (lastValid_) appendMmltSplat(last_, out);
}

std::vector<ParamSpec> RjmltMethod::params() const {
  ParamSpec technique;
  technique.name = "technique-step";
  technique.type = ParamSpec::Type::Double;
  technique.defaultValue = fmt::format("{}", RjmltSettings{}.techniqueProb);  // one default: the chain's
  technique.help = "probability of a technique change (a reversible jump) per mutation";
  technique.min = 0;
  technique.max = 1;
  std::vector<ParamSpec> all = PrimarySampleChainMethod::params();
  all.push_back(technique);
  all.push_back(mmltBSampleParam());
  return all;
}

// The chain's default, written once (RjmltSettings): 0.1 as a double rounded to float, the same float as 0.1f.
float RjmltMethod::defaultLargeStepProb() const { return float(RjmltSettings{}.largeStepProb); }

void RjmltMethod::validate(const RenderSettings& settings) const {
  PrimarySampleChainMethod::validate(settings);
  const double pTechnique = param(settings, "technique-step");
  const double pLarge = resolveChainSettings(*this, settings).largeStepProb;
  if (!(pLarge + pTechnique <= 1))
    throw std::invalid_argument("settings: rjmlt's large-step (" + std::to_string(pLarge) +
                                ") and technique-step (" + std::to_string(pTechnique) + ") probabilities sum to more than 1");
}

std::unique_ptr<PssTarget> RjmltMethod::makeTarget(const RenderScene& scene, const RenderSettings& settings) const {
  return std::make_unique<RjmltTarget>(scene, settings.integrator);
}

std::unique_ptr<ChainState> RjmltMethod::makeState(KelemenSource&, const RenderSettings&) const {
  throw std::logic_error("rjmlt: the chain state needs its target and path length (makeChainState)");
}

std::unique_ptr<ChainState> RjmltMethod::makeChainState(KelemenSource& source, const RenderSettings& settings,
                                                        PssTarget& target, int pathLength) const {
  auto* t = dynamic_cast<RjmltTarget*>(&target);
  if (!t) throw std::logic_error("rjmlt: the chain's target is not rjmlt's");
  RjmltSettings rs;
  rs.largeStepProb = settings.largeStepProb;  // the plan's, resolved (resolveChainSettings)
  rs.techniqueProb = param(settings, "technique-step");
  auto state = std::make_unique<RjmltState>(t->scene(), source, pathLength, t->heuristic(), rs,
                                            chainRng(source.jobSeed(), source.chainIndex(), 2));
  state->adopt(t->lastPath(), t->lastValid());
  t->attach(state.get());
  return state;
}

}  // namespace mlt
