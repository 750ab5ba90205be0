// The method "veach-mlt": Veach's path-space Metropolis light transport (Veach 1997, ch. 11; Veach and
// Guibas 1997) with all five of its mutations and a sixth of this project's, the deep lens perturbation,
// off by default (docs/VEACH.md). Registered in registry.cpp. Its plan is the pssmlt-bdpt bootstrap and
// chain allocation (this class is the ChainJobSpec that plans it: the bdpt target, one path-length slot);
// its units are path-space chains (veach_job.h), not Kelemen chains.
//
// Parameters (RenderSettings::params, CLI --<name>):
//   veach-bidir, veach-lens, veach-caustic, veach-multichain, veach-lens-subpath, veach-deep-lens
//                                         selection weights (>= 0)
//   veach-lens-r1, veach-lens-r2          lens / multi-chain film step range in pixels (r2 0: 5% of sqrt(P))
//   veach-caustic-theta1, veach-caustic-theta2   caustic / multi-chain angle range in radians
//   veach-light-view                      light-view pass: spp per mutation per pixel (0: off; light_view.h)
#pragma once
#include "common/job/mlt_job.h"
#include "common/methods/method.h"
#include "common/methods/veach/mutations.h"

namespace mlt {

class VeachMltMethod final : public RenderMethod, public ChainJobSpec {
 public:
  std::string name() const override { return "veach-mlt"; }
  std::string description() const override {
    return "Veach's path-space MLT: bidirectional mutation, lens, caustic and multi-chain perturbations, lens subpath "
           "mutation";
  }
  MethodFamily family() const override { return MethodFamily::MarkovChain; }
  std::vector<std::string> mutationKinds() const override { return veach::mutationKindNames(); }
  std::vector<ParamSpec> params() const override;
  void validate(const RenderSettings& settings) const override;
  JobPlan plan(const RenderScene& scene, const RenderSettings& settings) const override;
  PartialResult runUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) const override;
  std::vector<Color> develop(const JobPlan& plan, const PartialResult& merged) const override;
  void addMetadata(const JobPlan& plan, const PartialResult& merged, ImageMetadata& metadata) const override;
  // The chain layers, and the light-view pass's layer (light_view.h).
  size_t filmLayers(const JobPlan& plan) const override;

  // ChainJobSpec (the bootstrap and chain allocation of pssmlt-bdpt).
  bool chainsPerLength() const override { return false; }
  bool allowsSeparateDirect() const override { return true; }  // veach_job.h
  bool allowsEmissionPass() const override { return false; }     // its light-view pass renders those paths
  // No large steps (b's samples are separate candidates, veach_job.h): expected values only.
  MltSplatting defaultSplatting() const override { return MltSplatting::ExpectedValue; }
  bool supportsKelemenMis() const override { return false; }
  std::unique_ptr<PssTarget> makeTarget(const RenderScene& scene, const RenderSettings& settings) const override;
  std::unique_ptr<ChainState> makeState(KelemenSource& source, const RenderSettings& settings) const override;
  // A candidate is a bdpt sample (every strategy, ~depth^2 connections) against a mutation that retraces a
  // part of one path (~depth): measured (docs/RESULTS.md's throughput columns, bdpt samples/s against
  // veach-mlt mutations/s) 2.9x and 4.6x at max depth 5 (glossy-plates, cornell-box), 5.8x and 6.2x at 12
  // (caustic-mirror, door-ajar); the count-sized bootstrap took 13-25% of the job there before this.
  // Modelled as 2 + depth / 3 (3.7 at 5, 6 at 12), at most 8 (also for unlimited depth).
  double candidateCost(const RenderSettings& settings) const override;
  // With the light-view pass on: the same settings with it off (its chains carry the pass; veach_job.h).
  std::optional<RenderSettings> settingsWhenNoChains(const RenderSettings& settings) const override;

  // The mutation settings from the params (defaults where unset).
  veach::MutationSettings mutationSettings(const RenderSettings& settings) const;
};

}  // namespace mlt
