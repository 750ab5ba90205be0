#include "common/mlt/chain.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "common/mlt/target.h"

namespace mlt {

ChainCounts runChain(ChainState& state, ChainTarget& target, const ChainConfig& config, ChainSink& sink,
                     Pcg32& acceptRng, uint64_t mutations, PathContribution& current, double cx,
                     PathContribution& scratch) {
  if (!(cx > 0)) throw std::invalid_argument("runChain: the start state has target value " + std::to_string(cx) +
                                             " (must be > 0)");
  const bool mis = config.splatting == ChainSplatting::KelemenMIS;
  if (mis && !(config.b > 0)) throw std::invalid_argument("runChain: Kelemen MIS splatting needs b > 0");
  const double bPlarge = mis ? config.b * config.largeStepProb : 0.0;

  using Clock = std::chrono::steady_clock;
  double timedSeconds[kMaxMutationKinds] = {};
  uint64_t timedSteps[kMaxMutationKinds] = {};

  ChainCounts counts;
  PathContribution* x = &current;
  PathContribution* y = &scratch;
  double xWeight = 0;  // accumulated, not yet splatted weight of the current state
  for (uint64_t m = 0; m < mutations; ++m) {
    const bool timed = m % kMoveTimingStride == 0;
    const Clock::time_point stepStart = timed ? Clock::now() : Clock::time_point{};
    const Proposal p = state.propose();
    y->clear();
    target.evaluate(*y);
    const double cy = targetFunction(*y, config.target);
    double ratio = p.tRatio * cy / cx;
    if (config.acceptancePower != 1) ratio = std::pow(ratio, config.acceptancePower);
    const double a = std::isfinite(ratio) ? std::min(1.0, ratio) : (cy > 0 ? 1.0 : 0.0);
    const int kind = p.kind;
    if (kind < 0 || kind >= kMaxMutationKinds)
      throw std::invalid_argument("runChain: mutation kind " + std::to_string(kind) + " out of range");
    ++counts.proposed[kind];
    if (p.independent) {
      counts.largeSteps.add(cy, config.tau);
      if (config.target.shaped()) counts.largeStepsLuminance.add(targetFunction(*y), config.luminanceTau);
      if (config.stratifyLargeSteps) {
        const Vec2 u = state.stratumPoint();
        if (u.x >= 0 && u.y >= 0) sink.stratumSample(u, std::min(cy, config.tau));
      }
    }

    double wy, wx;
    if (mis) {
      // The Metropolis share (a and 1 - a) here; a large step's own share, L = 1, into the sink's
      // large-step layer, which is developed with this chain's b, not the refined one (chain.h).
      if (p.independent && !y->splats.empty()) sink.largeStepSplat(*y, 1.0 / (cy + bPlarge));
      wy = cy > 0 ? a / (cy + bPlarge) : 0.0;
      wx = (1 - a) / (cx + bPlarge);
    } else {
      wy = cy > 0 ? a / cy : 0.0;
      wx = (1 - a) / cx;
    }
    xWeight += wx;

    if (a > 0 && acceptRng.uniformDouble() < a) {
      ++counts.accepted[kind];
      if (xWeight > 0) sink.splat(*x, xWeight);
      std::swap(x, y);
      cx = cy;
      xWeight = wy;
      state.accept();
    } else {
      if (wy > 0 && !y->splats.empty()) sink.splat(*y, wy);
      state.reject();
    }
    if (timed) {
      timedSeconds[kind] += std::chrono::duration<double>(Clock::now() - stepStart).count();
      ++timedSteps[kind];
    }
  }
  double allSeconds = 0;
  uint64_t allSteps = 0;
  for (int k = 0; k < kMaxMutationKinds; ++k) {
    allSeconds += timedSeconds[k];
    allSteps += timedSteps[k];
  }
  for (int k = 0; k < kMaxMutationKinds; ++k) {
    const double perStep = timedSteps[k] > 0 ? timedSeconds[k] / double(timedSteps[k])
                                             : allSeconds / double(std::max<uint64_t>(allSteps, 1));
    counts.seconds[k] = perStep * double(counts.proposed[k]);
  }
  if (xWeight > 0) sink.splat(*x, xWeight);
  if (x != &current) std::swap(current, scratch);  // O(1): swaps the vectors' buffers
  return counts;
}

}  // namespace mlt
