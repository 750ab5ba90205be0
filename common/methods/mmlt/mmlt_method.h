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

// One technique of length k per evaluation (the paper's target for chain k).
class MmltTarget final : public PssTarget {
 public:
  MmltTarget(const RenderScene& scene, const IntegratorSettings& integrator);
  void evaluate(SampleSource& source, int pathLength, PathContribution& out) override;

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
  std::unique_ptr<PssTarget> makeTarget(const RenderScene& scene, const RenderSettings& settings) const override;
};

}  // namespace mlt
