// The method "pssmlt-bdpt": primary-sample-space MLT over bidirectional path tracing (all strategies per sample).
// Its target is the bdpt evaluator on the chain's numbers (EvaluatorPssTarget, pss_method.h); one
// path-length slot for all lengths.
#pragma once
#include "common/methods/pss_method.h"

namespace mlt {

class PssmltBdptMethod final : public PrimarySampleChainMethod {
 public:
  std::string name() const override { return "pssmlt-bdpt"; }
  std::string description() const override { return "primary-sample-space MLT over bidirectional path tracing (all strategies per sample)"; }
  bool chainsPerLength() const override { return false; }
  bool allowsSeparateDirect() const override { return true; }
  // A mutation is a whole bdpt sample (all strategies): at 16 s, 256x256, one thread, mmlt ran 2.6-4.5x its
  // mutations per pixel on the four scenes that take the direct pass (geometric mean 3.6; docs/CHAINS.md)
  double mutationCost() const override { return 4.0; }
  std::unique_ptr<PssTarget> makeTarget(const RenderScene& scene, const RenderSettings& settings) const override;
};

}  // namespace mlt
