// Veach's path-space chain on the shared chain loop (common/mlt/chain.h runChain): the state is a Path,
// a proposal is one of the mutations of mutations.h, the target evaluates f(y) (path.h) into one splat.
//
// Mutation choice (Veach 1997, sec. 11.4.5): fixed weights w_t, restricted to the moves applicable to
// the current path, P(t | x) = w_t / sum over t' applicable to x of w_t'. The chosen move's density and
// its choice probability enter the ratio reported to the loop:
//     Proposal::tRatio = P(t | y) T_t(y -> x) / (P(t | x) T_t(x -> y)),
// so the loop's a = min(1, tRatio c(y) / c(x)) is Veach's eq. 11.3 with c = luminance of f. Each move
// satisfies detailed balance with respect to f on its own, hence so does the mixture.
//
// Start states (Veach 1997, sec. 11.3.1, resampling the bootstrap): a bootstrap candidate u of
// pssmlt-bdpt is drawn in proportion to c(u) = lum(sum over strategies (s,t) of w_st C_st(u)) (the plan's
// alias table), then one of its strategies in proportion to lum(w_st C_st). The path x_st(u) of a
// strategy has density p_st, so x has density sum_st p_st lum(w_st f / p_st) / b = lum(f(x)) / b:
// chains start in the stationary distribution (no start-up bias), with the same b as pssmlt-bdpt.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>

#include "common/integrators/bdpt.h"
#include "common/integrators/path_evaluator.h"
#include "common/methods/veach/mutations.h"
#include "common/methods/veach/path.h"
#include "common/mlt/chain.h"
#include "common/sampler/sample_source.h"

namespace mlt::veach {

class VeachChainState final : public ChainState {
 public:
  VeachChainState(const PathSpace& space, const MutationSettings& settings, Path start, Pcg32 rng);
  Proposal propose() override;
  void accept() override;
  void reject() override {}

  const Path& current() const { return x_; }
  Color currentF() const { return fx_; }
  Vec2 currentRaster() const { return rasterX_; }
  // The proposal of the last propose(): f(y) and its raster (f = 0 for a move that failed).
  Color proposalF() const { return fy_; }
  Vec2 proposalRaster() const { return rasterY_; }
  const Path& proposal() const { return y_; }
  // P(t | x) (0 if t is not applicable to x).
  double choiceProbability(int kind, const Path& x) const;
  const Mutation& mutation(int kind) const { return *moves_[kind]; }

 private:
  const PathSpace& space_;
  MutationSettings settings_;
  std::unique_ptr<Mutation> moves_[kNumKinds];
  Path x_, y_;
  Color fx_, fy_;
  Vec2 rasterX_, rasterY_;
  Pcg32 rng_;
};

// The loop's target: the proposal's f as one splat at its raster position.
class VeachChainTarget final : public ChainTarget {
 public:
  explicit VeachChainTarget(const VeachChainState& state) : state_(state) {}
  void evaluate(PathContribution& out) override;

 private:
  const VeachChainState& state_;
};

// The current path as a contribution (for the loop's start state).
void currentContribution(const VeachChainState& state, PathContribution& out);

// Same vertex positions.
bool samePath(const Path& a, const Path& b);

// ---- start states -------------------------------------------------------------------------------------
struct StartPath {
  Path path;
  double candidateC = 0;  // c(u) of the whole bdpt sample (must equal the bootstrap's value)
  int s = -1, t = -1;     // the strategy chosen
};
// The path of bdpt strategy (s, t): light[0..s-1] then camera[t-1..0], `sampled` replacing the resampled
// end (s = 1: the light point; t = 1: the lens point); uLens = the camera stream's lens sample. Vertices
// strictly inside a subpath are specular where bdpt sampled a Dirac lobe there; connection ends are not.
Path bdptStrategyPath(const Vertex* light, int s, const Vertex* camera, int t, const Vertex& sampled, Vec2 uLens);
// Replays the bdpt sample of `source` (the bootstrap's candidate) and picks one strategy in proportion to
// lum(w C) with uPick in [0,1); strategies of fewer than space.minEdges() segments are left out of both
// (separateDirect, as the bootstrap's target leaves them out). nullopt if no strategy carries light or the chosen path has f = 0.
std::optional<StartPath> startPathFromSample(const PathSpace& space, const IntegratorSettings& integrator,
                                             SampleSource& source, double uPick);

}  // namespace mlt::veach
