// The method "mmlt": multiplexed MLT (Hachisuka et al. 2014). Chains per path length k (segments), each
// sampling one bdpt technique (s, t) at a time: Connect[kConnectTechniqueDim] picks s uniformly among the
// nTechniques(k) strategies, t = k + 1 - s; the contribution is C(s,t) * w(s,t) * nTechniques(k), so that
// summing over the uniform technique choice gives sum_(s,t) w C = the bdpt estimate of length k.
#pragma once
#include "common/integrators/bdpt.h"
#include "common/methods/pss_method.h"

namespace mlt {

// Strategies bdpt weights for a path of k segments: (s, t) with s + t = k + 1, t >= 1, without (1, 1)
// (see bdpt.h). k = 1: only (0, 2); k >= 2: s = 0..k.
int mmltTechniqueCount(int k);

// mmlt's Rao-Blackwellized b sample of length k (develop.h (D9)): c_k = n w lum(C) of the technique chosen by a
// coordinate nothing else reads, averaged over that choice: lum(sum_s w_s C_s), every technique on the same
// numbers (evaluateLength). The same as c_k where k has one technique (k = 1).
double mmltBSample(const RenderScene& scene, SampleSource& source, int k, MisHeuristic heuristic, BdptWorkspace& ws);
// Its stride, the parameter "b-sample-every" of mmlt and rjmlt (ChainJobSpec::mutationsPerBSample): mutations
// per b sample, 0 = b refined by the large steps' c. kDefaultBSampleEvery: measured, docs/CHAINS.md.
inline constexpr const char* kDefaultBSampleEvery = "0";
ParamSpec mmltBSampleParam();
uint64_t mmltMutationsPerBSample(const RenderMethod& method, const RenderSettings& settings, int k);

// One technique of length k per evaluation (the paper's target for chain k).
class MmltTarget final : public PssTarget {
 public:
  MmltTarget(const RenderScene& scene, const IntegratorSettings& integrator);
  void evaluate(SampleSource& source, int pathLength, PathContribution& out) override;
  double bSample(SampleSource& source, int pathLength) override {
    return mmltBSample(scene_, source, pathLength, integrator_.heuristic, ws_);
  }

 private:
  const RenderScene& scene_;
  IntegratorSettings integrator_;
  BdptWorkspace ws_;
};

class MmltMethod final : public PrimarySampleChainMethod {
 public:
  std::string name() const override { return "mmlt"; }
  std::string description() const override {
    return "multiplexed MLT (Hachisuka et al. 2014): chains per path length over one bdpt technique at a time";
  }
  bool chainsPerLength() const override { return true; }
  bool allowsSeparateDirect() const override { return true; }
  std::vector<ParamSpec> params() const override;
  uint64_t mutationsPerBSample(const RenderSettings& settings, int pathLength) const override {
    return mmltMutationsPerBSample(*this, settings, pathLength);
  }
  std::unique_ptr<PssTarget> makeTarget(const RenderScene& scene, const RenderSettings& settings) const override;
};

}  // namespace mlt
