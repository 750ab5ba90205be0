// The family of Markov chain methods over primary samples (Kelemen et al. 2002): pssmlt, pssmlt-bdpt,
// mmlt. A method of this family supplies its target function (a PssTarget: primary samples -> splats)
// and says whether it keeps chains per path length; the bootstrap, the chain allocation, the chain loop
// (common/mlt/chain.h) over a Kelemen sample source, the refined b and the development are shared
// (common/job/mlt_job.h). The chain state defaults to Kelemen's large and small steps (PssState); a
// method with other moves (reversible jumps) overrides makeState and mutationKinds.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "common/job/mlt_job.h"
#include "common/methods/method.h"

namespace mlt {

class PathEvaluator;

// The target's defaults (params "target", "target-floor", "target-power"; docs/CHAINS.md, "A relative
// target" and "A tempered target": measured).
inline constexpr const char* kDefaultTarget = "luminance";
inline constexpr const char* kDefaultTargetFloor = "0.5";
inline constexpr const char* kDefaultTargetPower = "1";

class PrimarySampleChainMethod : public RenderMethod, public ChainJobSpec {
 public:
  std::string name() const override = 0;
  MethodFamily family() const final { return MethodFamily::MarkovChain; }
  std::vector<std::string> mutationKinds() const override { return {"large", "small"}; }  // index = MutationType
  std::unique_ptr<ChainState> makeState(KelemenSource& source, const RenderSettings& settings) const override;
  // The target (common/mlt/importance.h, target.h): "target" luminance (the default) or relative,
  // "target-floor" kappa of the relative one, and "target-power" beta of either (T1). A method with
  // parameters of its own appends them to these.
  std::vector<ParamSpec> params() const override;
  double importanceFloor(const RenderSettings& settings) const override;
  double targetPower(const RenderSettings& settings) const override;

  void validate(const RenderSettings& settings) const override;
  JobPlan plan(const RenderScene& scene, const RenderSettings& settings) const override;
  PartialResult runUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) const override;
  std::vector<Color> develop(const JobPlan& plan, const PartialResult& merged) const override;
  void addMetadata(const JobPlan& plan, const PartialResult& merged, ImageMetadata& metadata) const override;
};

// A method of this family by name (the local renderer plans a time budget from one bootstrap through it);
// nullptr if `name` is registered but of another kind. Throws std::invalid_argument for an unknown name.
const PrimarySampleChainMethod* findPrimarySampleChainMethod(const std::string& name);
// A method whose jobs the shared bootstrap and chain allocation plan (the methods of this family, and
// veach-mlt, whose path-space chains start from pssmlt-bdpt's bootstrap); nullptr otherwise. Throws
// std::invalid_argument for an unknown name. The convenience functions below accept all of them.
const ChainJobSpec* findChainJobSpec(const std::string& name);

// The target of pssmlt and pssmlt-bdpt: a path evaluator on the chain's numbers (the film position from
// the camera stream). directSegments > 0 (directPassSegments): paths of at most that many segments are
// dropped (rendered by the direct pass instead); that needs splats labelled with (s, t).
class EvaluatorPssTarget final : public PssTarget {
 public:
  EvaluatorPssTarget(std::unique_ptr<PathEvaluator> evaluator, int directSegments);
  ~EvaluatorPssTarget() override;
  void evaluate(SampleSource& source, int pathLength, PathContribution& out) override;

 private:
  std::unique_ptr<PathEvaluator> evaluator_;
  int directSegments_;
};

// Convenience over the registry for tools and tests: the functions of mlt_job.h for settings.method.
uint64_t bootstrapPerLength(const RenderSettings& settings);
std::vector<int> chainPathLengths(const RenderSettings& settings);
void validateMarkovChainSettings(const RenderSettings& settings);
MarkovChainBootstrap bootstrapMarkovChainJob(const RenderScene& scene, const RenderSettings& settings,
                                             const MarkovChainBootstrap* earlier = nullptr);
JobPlan planMarkovChainJob(const RenderScene& scene, const RenderSettings& settings, const MarkovChainBootstrap& boot);

}  // namespace mlt
