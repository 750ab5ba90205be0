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

std::vector<ParamSpec> PrimarySampleChainMethod::params() const {
  ParamSpec target;
  target.name = "target";
  target.type = ParamSpec::Type::Choice;
  target.defaultValue = kDefaultTarget;
  target.help = "the chains' target: relative (luminance over a pilot's estimate of the pixel's brightness: mutations "
                "where the relative error is, common/mlt/importance.h) or luminance (Veach's and Kelemen's)";
  target.choices = {"relative", "luminance"};
  ParamSpec floor;
  floor.name = "target-floor";
  floor.type = ParamSpec::Type::Double;
  floor.defaultValue = kDefaultTargetFloor;
  floor.help = "relative target: pixels darker than this fraction of the image's mean brightness get mutations in "
               "proportion to their brightness, brighter ones alike";
  floor.min = 1e-3;
  floor.max = 1e3;
  ParamSpec power;
  power.name = "target-power";
  power.type = ParamSpec::Type::Double;
  power.defaultValue = kDefaultTargetPower;
  power.help = "the target raised to this power (common/mlt/target.h (T1)): below 1 a tempered target, flatter along "
               "paths and over the image (docs/CHAINS.md: about 1.5x lower error on glossy-plates at 0.65-0.8, "
               "several times higher on the caustic scenes)";
  power.min = 0.05;
  power.max = 1;
  return {target, floor, power};
}

double PrimarySampleChainMethod::importanceFloor(const RenderSettings& s) const {
  return paramText(s, "target") == "relative" ? param(s, "target-floor") : 0.0;
}

double PrimarySampleChainMethod::targetPower(const RenderSettings& s) const { return param(s, "target-power"); }

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
  // The target (importance.h): its name, the relative one's floor and its map's tile size (no map: the pilot
  // saw no light, and the target was luminance).
  m.strings["target"] = paramText(plan.settings, "target");
  if (plan.norm.targetPower != 1) m.numbers["targetPower"] = plan.norm.targetPower;
  if (const double floor = importanceFloor(plan.settings); floor > 0) {
    m.numbers["targetFloor"] = floor;
    m.numbers["importanceTileSize"] = plan.norm.importance.empty() ? 0 : plan.norm.importance.tileSize;
  }
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
