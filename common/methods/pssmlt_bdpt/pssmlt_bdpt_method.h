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
  std::unique_ptr<PssTarget> makeTarget(const RenderScene& scene, const RenderSettings& settings) const override;
};

}  // namespace mlt
