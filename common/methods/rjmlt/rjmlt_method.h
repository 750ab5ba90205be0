// The method "rjmlt": reversible-jump MLT (Bitterli et al. 2017) - multiplexed MLT's chains per path
// length with a third move that changes the bdpt technique and keeps the path (rjmlt_chain.h). The
// bootstrap, b_k, chain allocation, splatting and development are MMLT's (the target function is the
// same: C(s,t) w(s,t) n); only the chain state differs.
// Moves: large steps with the common large-step probability (--large-step; rjmlt's default 0.1, the issue's
// 10 / 85 / 5 split, measured better than the other methods' 0.3 on all four bundled scenes: docs/SWEEP.md),
// technique changes with --technique-step (default 0.02: 0.86x the relMSE of the 0.05 at equal time over
// 84 paired runs on the seven bundled scenes, docs/SWEEP.md), small steps otherwise. Kinds: "large", "small",
// "technique".
#pragma once
#include "common/integrators/bdpt.h"
#include "common/methods/mmlt/mmlt_method.h"
#include "common/methods/pss_method.h"
#include "common/methods/rjmlt/path_inversion.h"

namespace mlt {

class RjmltState;

// MMLT's target; once a chain's RjmltState is attached, evaluation is the state's (it knows which
// technique the proposal uses and checks that a jump re-traced the same path).
class RjmltTarget final : public PssTarget {
 public:
  RjmltTarget(const RenderScene& scene, const IntegratorSettings& integrator);
  void evaluate(SampleSource& source, int pathLength, PathContribution& out) override;
  // MMLT's b sample (mmlt_method.h), in a workspace of its own (ws_ holds the attached state's path).
  double bSample(SampleSource& source, int pathLength) override {
    return mmltBSample(scene_, source, pathLength, integrator_.heuristic, bSampleWs_);
  }
  const RenderScene& scene() const { return scene_; }
  MisHeuristic heuristic() const { return integrator_.heuristic; }
  // The path of the last evaluation before a state was attached (the chain's replayed start state).
  const MmltPath& lastPath() const { return last_; }
  bool lastValid() const { return lastValid_; }
  void attach(RjmltState* state) { state_ = state; }

 private:
  const RenderScene& scene_;
  IntegratorSettings integrator_;
  BdptWorkspace ws_, bSampleWs_;
  MmltPath last_;
  bool lastValid_ = false;
  RjmltState* state_ = nullptr;
};

class RjmltMethod final : public PrimarySampleChainMethod {
 public:
  std::string name() const override { return "rjmlt"; }
  std::string description() const override {
    return "reversible-jump MLT (Bitterli et al. 2017): mmlt with technique changes that keep the path";
  }
  bool chainsPerLength() const override { return true; }
  bool allowsSeparateDirect() const override { return true; }
  std::vector<std::string> mutationKinds() const override { return {"large", "small", "technique"}; }
  float defaultLargeStepProb() const override;  // RjmltSettings' (rjmlt_chain.h), where the value is written
  std::vector<ParamSpec> params() const override;
  uint64_t mutationsPerBSample(const RenderSettings& settings, int pathLength) const override {
    return mmltMutationsPerBSample(*this, settings, pathLength);
  }
  void validate(const RenderSettings& settings) const override;
  std::unique_ptr<PssTarget> makeTarget(const RenderScene& scene, const RenderSettings& settings) const override;
  // rjmlt's state needs its chain's target and length: makeChainState. makeState alone throws.
  std::unique_ptr<ChainState> makeState(KelemenSource& source, const RenderSettings& settings) const override;
  std::unique_ptr<ChainState> makeChainState(KelemenSource& source, const RenderSettings& settings, PssTarget& target,
                                             int pathLength) const override;
};

}  // namespace mlt
