// The method "pssmlt": primary-sample-space MLT (Kelemen et al. 2002) over the path tracer.
// Its target is the pt evaluator on the chain's numbers (EvaluatorPssTarget, pss_method.h); one
// path-length slot for all lengths.
#pragma once
#include "common/methods/pss_method.h"

namespace mlt {

class PssmltMethod final : public PrimarySampleChainMethod {
 public:
  std::string name() const override { return "pssmlt"; }
  std::string description() const override { return "primary-sample-space MLT (Kelemen et al. 2002) over the path tracer"; }
  bool chainsPerLength() const override { return false; }
  bool allowsSeparateDirect() const override { return false; }
  std::unique_ptr<PssTarget> makeTarget(const RenderScene& scene, const RenderSettings& settings) const override;
};

}  // namespace mlt
