#include "common/methods/pss_method.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/integrators/path_evaluator.h"
#include "common/methods/chain_report.h"
#include "common/methods/registry.h"

namespace mlt {

std::unique_ptr<ChainState> PrimarySampleChainMethod::makeState(KelemenSource& source, const RenderSettings&) const {
  return std::make_unique<PssState>(source);
}

void PrimarySampleChainMethod::validate(const RenderSettings& s) const {
  RenderMethod::validate(s);
  validateChainWorkSettings(s);
  validateSeparateDirect(*this, s);
  KelemenSource kernel(kelemenParams(resolveChainSettings(*this, s)), 0, 0, 0);  // throws on bad kernel parameters
  chainPathLengths(*this, s);                        // chains per length: a valid max depth
}

JobPlan PrimarySampleChainMethod::plan(const RenderScene& scene, const RenderSettings& settings) const {
  return planMarkovChainJob(*this, scene, settings);
}

PartialResult PrimarySampleChainMethod::runUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) const {
  return runMarkovChain(*this, scene, plan, unit);
}

std::vector<Color> PrimarySampleChainMethod::develop(const JobPlan& plan, const PartialResult& merged) const {
  return developMarkovChainImage(plan, merged);
}

void PrimarySampleChainMethod::addMetadata(const JobPlan& plan, const PartialResult& merged, ImageMetadata& m) const {
  addChainMetadata(makeChainReport(plan, merged), m);  // includes the chain settings (largeStepProb, ...)
}

const PrimarySampleChainMethod* findPrimarySampleChainMethod(const std::string& name) {
  return dynamic_cast<const PrimarySampleChainMethod*>(&findMethod(name));
}

const ChainJobSpec* findChainJobSpec(const std::string& name) {
  return dynamic_cast<const ChainJobSpec*>(&findMethod(name));
}

namespace {
const ChainJobSpec& spec(const RenderSettings& s) {
  const ChainJobSpec* m = findChainJobSpec(s.method);
  if (!m) throw std::invalid_argument("settings: method " + s.method + " is not a Markov chain method with a bootstrap");
  return *m;
}
}  // namespace

uint64_t bootstrapPerLength(const RenderSettings& s) { return bootstrapPerLength(spec(s), s); }
std::vector<int> chainPathLengths(const RenderSettings& s) { return chainPathLengths(spec(s), s); }
void validateMarkovChainSettings(const RenderSettings& s) { validateMarkovChainSettings(spec(s), s); }
MarkovChainBootstrap bootstrapMarkovChainJob(const RenderScene& scene, const RenderSettings& s,
                                             const MarkovChainBootstrap* earlier) {
  return bootstrapMarkovChainJob(spec(s), scene, s, earlier);
}
JobPlan planMarkovChainJob(const RenderScene& scene, const RenderSettings& s, const MarkovChainBootstrap& boot) {
  return planMarkovChainJob(spec(s), scene, s, boot);
}

EvaluatorPssTarget::EvaluatorPssTarget(std::unique_ptr<PathEvaluator> evaluator, int directSegments)
    : evaluator_(std::move(evaluator)), directSegments_(directSegments) {}
EvaluatorPssTarget::~EvaluatorPssTarget() = default;

void EvaluatorPssTarget::evaluate(SampleSource& source, int /*pathLength*/, PathContribution& out) {
  out.clear();
  evaluator_->evaluate(source, nullptr, out);
  if (directSegments_ <= 0) return;
  // A path of s + t vertices has s + t - 1 segments. Splats without (s, t) cannot be classified.
  for (const Splat& sp : out.splats)
    if (sp.s < 0 || sp.t < 0)
      throw std::logic_error("separateDirect: the path evaluator does not label its splats with (s, t)");
  std::erase_if(out.splats, [this](const Splat& sp) { return sp.s + sp.t - 1 <= directSegments_; });
}

}  // namespace mlt
