#include "common/methods/veach/veach_method.h"

#include <algorithm>

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/integrators/evaluators.h"
#include "common/methods/chain_report.h"
#include "common/methods/pss_method.h"
#include "common/methods/veach/light_view.h"
#include "common/methods/veach/veach_job.h"

namespace mlt {

namespace {
const char* const kWeightParams[veach::kNumKinds] = {"veach-bidir", "veach-lens", "veach-caustic", "veach-multichain",
                                                     "veach-lens-subpath", "veach-deep-lens"};
}  // namespace

std::vector<ParamSpec> VeachMltMethod::params() const {
  const veach::MutationSettings d;
  std::vector<ParamSpec> p;
  for (int k = 0; k < veach::kNumKinds; ++k)
    p.push_back({kWeightParams[k], ParamSpec::Type::Double, fmt::format("{}", d.weight[k]),
                 "selection weight of the " + veach::mutationKindNames()[k] + " mutation (0: off)", 0, -1, {}});
  p.push_back({"veach-lens-r1", ParamSpec::Type::Double, fmt::format("{}", d.r1),
               "lens/multi-chain perturbation: smallest film step (pixels)", 1e-6, -1, {}});
  p.push_back({"veach-lens-r2", ParamSpec::Type::Double, fmt::format("{}", d.r2),
               "lens/multi-chain perturbation: largest film step (pixels; 0 = 5% of sqrt(pixels))", 0, -1, {}});
  p.push_back({"veach-caustic-theta1", ParamSpec::Type::Double, fmt::format("{}", d.theta1),
               "caustic/multi-chain perturbation: smallest angle (radians)", 1e-9, 3.14159, {}});
  p.push_back({"veach-caustic-theta2", ParamSpec::Type::Double, fmt::format("{}", d.theta2),
               "caustic/multi-chain perturbation: largest angle (radians)", 1e-9, 3.14159, {}});
  p.push_back({"veach-light-view", ParamSpec::Type::Double, fmt::format("{}", d.lightView),
               "light-view pass (lights seen directly or through mirrors and glass, by camera rays): samples per "
               "pixel per mutation per pixel (0: off, the chains carry them)", 0, 1000, {}});
  return p;
}

veach::MutationSettings VeachMltMethod::mutationSettings(const RenderSettings& s) const {
  veach::MutationSettings m;
  for (int k = 0; k < veach::kNumKinds; ++k) m.weight[k] = param(s, kWeightParams[k]);
  m.r1 = param(s, "veach-lens-r1");
  m.r2 = param(s, "veach-lens-r2");
  m.theta1 = param(s, "veach-caustic-theta1");
  m.theta2 = param(s, "veach-caustic-theta2");
  m.lightView = param(s, "veach-light-view");
  return m;
}

void VeachMltMethod::validate(const RenderSettings& s) const {
  RenderMethod::validate(s);
  validateChainWorkSettings(s);
  validateSeparateDirect(*this, s);
  const veach::MutationSettings m = mutationSettings(s);
  double sum = 0;
  for (double w : m.weight) sum += w;
  if (!(m.weight[veach::kBidir] > 0))
    throw std::invalid_argument("settings: veach-bidir must be > 0 (the bidirectional mutation makes the chain ergodic)");
  if (!(sum > 0)) throw std::invalid_argument("settings: veach-mlt needs a mutation with a positive weight");
  if (!(m.theta1 < m.theta2)) throw std::invalid_argument("settings: veach-caustic-theta1 must be < veach-caustic-theta2");
  if (m.r2 > 0 && !(m.r1 < m.r2)) throw std::invalid_argument("settings: veach-lens-r1 must be < veach-lens-r2");
}

JobPlan VeachMltMethod::plan(const RenderScene& scene, const RenderSettings& settings) const {
  return veach::planVeachJob(scene, settings);
}

PartialResult VeachMltMethod::runUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) const {
  return veach::runVeachChain(scene, plan, unit, mutationSettings(plan.settings));
}

std::vector<Color> VeachMltMethod::develop(const JobPlan& plan, const PartialResult& merged) const {
  return veach::developVeachImage(plan, merged, mutationSettings(plan.settings));
}

void VeachMltMethod::addMetadata(const JobPlan& plan, const PartialResult& merged, ImageMetadata& m) const {
  addChainMetadata(makeChainReport(plan, merged), m);  // b, acceptance per mutation kind (mutationKinds())
  m.numbers["lightViewSpp"] = veach::lightViewSpp(mutationSettings(plan.settings).lightView, plan.settings.mutationsPerPixel);
}

size_t VeachMltMethod::filmLayers(const JobPlan& plan) const {
  const size_t chains = RenderMethod::filmLayers(plan);
  const bool pass = veach::lightViewSpp(mutationSettings(plan.settings).lightView, plan.settings.mutationsPerPixel) > 0;
  return pass && plan.norm.totalMutations > 0 ? std::max(chains, veach::lightViewLayer() + 1) : chains;
}

// A bdpt sample (all its strategies) in veach-mlt mutations. The results page measured the bootstrap at
// 3.5-5.6% of the job with 2 + depth / 3 (the 5.6%: cornell-box, depth 5, whose mutations are the cheapest
// relative to a candidate); 1.3x that keeps every scene there under 4.5% (target: 5%).
double VeachMltMethod::candidateCost(const RenderSettings& settings) const {
  const int depth = settings.integrator.maxDepth;
  return 1.3 * (depth < 0 ? 8.0 : std::clamp(2.0 + double(depth) / 3.0, 2.0, 8.0));
}

std::optional<RenderSettings> VeachMltMethod::settingsWhenNoChains(const RenderSettings& settings) const {
  if (!(mutationSettings(settings).lightView > 0)) return std::nullopt;
  RenderSettings s = settings;
  s.params["veach-light-view"] = "0";
  return s;
}

std::unique_ptr<PssTarget> VeachMltMethod::makeTarget(const RenderScene& scene, const RenderSettings& settings) const {
  // pssmlt-bdpt's target: c(u) of a bdpt sample, whose mean is b = integral of lum f over path space
  // (separateDirect: over the paths of more than kDirectMaxSegments segments, the chains' PathSpace).
  // With the light-view pass, also without the paths E S* L (light_view.h): c integrates the chains' f.
  const bool dropLightViews = mutationSettings(settings).lightView > 0;
  return std::make_unique<EvaluatorPssTarget>(std::make_unique<BdptEvaluator>(scene, settings.integrator, dropLightViews),
                                              directPassSegments(settings));
}

std::unique_ptr<ChainState> VeachMltMethod::makeState(KelemenSource&, const RenderSettings&) const {
  throw std::logic_error("veach-mlt: its chains run over paths (veach::runVeachChain), not over a Kelemen source");
}

}  // namespace mlt
