// Reversible-jump MLT's chain state (Bitterli et al. 2017, sec. 4-6) on top of the MMLT state of one path
// length k: a KelemenSource (the primary samples) and the bdpt technique (s, t), kept apart from the
// samples (small steps never change the technique). Three proposal kinds (chain.h: Proposal::kind):
//   "large"      (p_large)      every coordinate redrawn and the technique chosen uniformly: MMLT's
//                               independent proposal (its c(y) samples b, as MMLT's large steps do);
//   "small"      (rest)         Kelemen small step of the samples, same technique;
//   "technique"  (p_technique)  the reversible jump: the current path z is kept, a technique j is chosen
//                               with T(i->j), the samples become S_j^-1(z, gamma) (path_inversion.h)
//                               and the chain loop accepts with eq. 38:
//                                 a = min(1, T(j->i) |J[S_j^-1](z)| C_j(v) / (T(i->j) |J[S_i^-1](z)| C_i(u))),
//                               i.e. Proposal::tRatio = T(j->i) J_j / (T(i->j) J_i), c = the MMLT target.
//                               C_j J_j = f for every technique, so a = T(j->i) w_j / (T(i->j) w_i) (eq. 33).
//                               Proposals: MisWeight (default, the paper's sec. 4 choice): T(i->j) =
//                               w~_j(z), the power-heuristic weight computed from the Jacobians of every
//                               technique that can produce z (0 where a technique cannot, or connects at a
//                               Dirac vertex); j = i is allowed (it resamples the ambiguous coordinates).
//                               Then a ~ 1. Uniform: j != i uniformly, a = min(1, w_j / w_i).
// A jump whose inversion fails, or whose re-traced path is not the same path (numerical failure, sec. 6
// "final algorithm"), is rejected: c(y) = 0. The target (ChainTarget) is the same object: it traces the
// technique of the proposal, so MMLT's target value C w n is reproduced for every state.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "common/core/rng.h"
#include "common/integrators/bdpt.h"
#include "common/methods/rjmlt/path_inversion.h"
#include "common/mlt/chain.h"
#include "common/mlt/kelemen_source.h"

namespace mlt {

class RenderScene;

enum class TechniqueProposal { MisWeight, Uniform };

struct RjmltSettings {
  double largeStepProb = 0.1;   // large / small / technique = 10 / 88 / 2 %: the 10 / 85 / 5 with fewer jumps,
  double techniqueProb = 0.02;  // measured better at equal time on the bundled scenes (docs/SWEEP.md)
  TechniqueProposal proposal = TechniqueProposal::MisWeight;
  bool dropJacobian = false;    // tests only: Figure 3b's mistake (tRatio = 1), to show the tests can fail
};

// Mutation kinds of rjmlt (indices into rjmltKindNames).
enum RjmltKind : int { kRjmltLarge = 0, kRjmltSmall = 1, kRjmltTechnique = 2 };
inline constexpr const char* rjmltKindNames[] = {"large", "small", "technique"};

class RjmltState final : public ChainState, public ChainTarget {
 public:
  // source: the chain's KelemenSource at iteration 0 (replaying its start candidate); moves: the chain's
  // stream for move decisions and inversion numbers gamma.
  RjmltState(const RenderScene& scene, KelemenSource& source, int pathLength, MisHeuristic heuristic,
             const RjmltSettings& settings, Pcg32 moves);

  // Evaluates the start state (technique from Connect[kConnectTechniqueDim], as MMLT's target reads it)
  // and commits it. Returns its target value c.
  double start(PathContribution& out);
  // Takes over a start state that was already evaluated (by RjmltTarget) and accepted on the source.
  void adopt(const MmltPath& start, bool valid);

  Proposal propose() override;
  Vec2 stratumPoint() override { return source_.filmPositionNumbers(); }
  void accept() override;
  void reject() override;
  void evaluate(PathContribution& out) override;

  int technique() const { return s_; }  // current s (t = k + 1 - s)
  int pathLength() const { return k_; }
  // Jumps refused before evaluation (inversion failed) and after (the re-traced path differs).
  uint64_t inversionFailures() const { return inversionFailures_; }
  uint64_t retraceFailures() const { return retraceFailures_; }
  // Jumps to a technique other than the current one (the MisWeight proposal may pick the current one).
  uint64_t changesProposed() const { return changesProposed_; }
  uint64_t changesAccepted() const { return changesAccepted_; }

 private:
  void trace(int s, PathContribution& out);

  const RenderScene& scene_;
  KelemenSource& source_;
  int k_, n_;
  MisHeuristic heuristic_;
  RjmltSettings settings_;
  Pcg32 moves_;
  BdptWorkspace ws_;
  int s_ = 0, sProposed_ = 0;
  int kind_ = kRjmltSmall;
  bool jumpFailed_ = false;
  MmltPath current_, proposed_;
  std::vector<std::optional<PathInverse>> invs_;  // scratch of the MisWeight proposal
  std::vector<double> weights_;
  bool currentValid_ = false, proposedValid_ = false;
  uint64_t inversionFailures_ = 0, retraceFailures_ = 0, changesProposed_ = 0, changesAccepted_ = 0;
};

}  // namespace mlt
