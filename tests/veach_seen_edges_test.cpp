// PathSpace::f with `seen` (veach-mlt's chains pass their current state, whose edges all passed the
// visibility test) skips the shadow rays of the edges a proposal kept. It must give the same f, bit for
// bit, and the same raster as without it, for the proposals of every move, on scenes where edges do get
// blocked (the glass and mirror spheres inside the box; the box point- and spot-lit, with the spheres);
// and it must skip rays, or there is no saving. An edge matched by one end only, or by position without
// its normal, would let a blocked reconnection through: f would differ.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "common/methods/veach/path.h"
#include "common/methods/veach/veach_chain.h"
#include "common/mlt/target.h"
#include "common/render/accel.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

class ShadowCounter final : public RayObserver {
 public:
  void closestHit(const Ray&) override {}
  void shadow(const Ray&) override { ++count; }
  uint64_t count = 0;
};

bool sameBits(const Color& a, const Color& b) {
  return std::bit_cast<uint32_t>(a.r) == std::bit_cast<uint32_t>(b.r) &&
         std::bit_cast<uint32_t>(a.g) == std::bit_cast<uint32_t>(b.g) &&
         std::bit_cast<uint32_t>(a.b) == std::bit_cast<uint32_t>(b.b);
}

struct Tally {
  int proposals = 0, carrying = 0, mismatches = 0;
  uint64_t shadowWith = 0, shadowWithout = 0;
};

void run(const SceneDesc& desc, int maxDepth, Tally& t) {
  const std::unique_ptr<RenderScene> scene = RenderScene::build(desc);
  const veach::PathSpace space(*scene, maxDepth);
  IntegratorSettings integrator;
  integrator.maxDepth = maxDepth;
  int chains = 0;
  for (uint64_t i = 0; chains < 6 && i < 100000; ++i) {
    IndependentSource source(91, i);
    const std::optional<veach::StartPath> sp = veach::startPathFromSample(space, integrator, source, 0.5);
    if (!sp || !(luminance(space.f(sp->path, nullptr)) > 0)) continue;
    ++chains;
    veach::VeachChainState state(space, veach::MutationSettings{}, sp->path, Pcg32(92, i));
    Pcg32 acceptRng(93, i);
    for (int step = 0; step < 1500; ++step) {
      const Proposal p = state.propose();
      ++t.proposals;
      // The test's own evaluations of the proposal, with and without the current state as `seen`.
      ShadowCounter with, without;
      Vec2 rWith(-1, -1), rWithout(-1, -1);
      RayObserver* previous = setThreadRayObserver(&with);
      const Color fWith = space.f(state.proposal(), &rWith, &state.current());
      setThreadRayObserver(&without);
      const Color fWithout = space.f(state.proposal(), &rWithout);
      setThreadRayObserver(previous);
      t.shadowWith += with.count;
      t.shadowWithout += without.count;
      if (!fWithout.isBlack()) ++t.carrying;
      if (!sameBits(fWith, fWithout) || (!fWithout.isBlack() && (rWith.x != rWithout.x || rWith.y != rWithout.y))) {
        if (++t.mismatches <= 3)
          std::printf("mismatch: chain %d step %d kind %d: f with seen (%g %g %g), without (%g %g %g)\n", chains, step,
                      p.kind, fWith.r, fWith.g, fWith.b, fWithout.r, fWithout.g, fWithout.b);
      }
      // The chain's own f(y) is the one with `seen`.
      EXPECT_TRUE(sameBits(state.proposalF(), fWith) || state.proposalF().isBlack());
      const double cx = luminance(state.currentF()), cy = luminance(state.proposalF());
      const double a = p.tRatio > 0 && cy > 0 ? std::min(1.0, p.tRatio * cy / cx) : 0.0;
      if (acceptRng.uniformDouble() < a) state.accept();
      else state.reject();
    }
  }
  ASSERT_EQ(chains, 6);
}

TEST(VeachSeenEdges, SameFBitForBitWithFewerShadowRays) {
  Tally t;
  run(test::cornellBoxSpecular(16, 16), 5, t);
  run(test::cornellBoxSpecularPointSpot(16, 16), 5, t);
  std::printf("%d proposals, %d carrying light, %d mismatches; shadow rays %llu with seen, %llu without (%.2f)\n",
              t.proposals, t.carrying, t.mismatches, (unsigned long long)t.shadowWith,
              (unsigned long long)t.shadowWithout, double(t.shadowWith) / double(std::max<uint64_t>(t.shadowWithout, 1)));
  EXPECT_EQ(t.mismatches, 0);
  EXPECT_GT(t.carrying, 3000);  // the comparison covered proposals that carry light, not only failed ones
  EXPECT_LT(double(t.shadowWith), 0.8 * double(t.shadowWithout));
}

}  // namespace
}  // namespace mlt
