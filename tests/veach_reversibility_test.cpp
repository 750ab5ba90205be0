// Every proposal with f(y) > 0 has T(x -> y) > 0 and can be undone by the same move (T(y -> x) > 0, the
// move applicable at y; for the bidirectional mutation unless it deleted a specular vertex of x), for all
// five moves from many start paths: a scene with glass, mirror and a mirror wall (specular chains on both
// sides, multi-chain paths E S D S L), and the same lit by a point and a spot light (delta-position light
// vertices: re-sampled by bidir, kept by the other moves, caustic chains next to the light).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "common/methods/veach/mutations.h"
#include "common/methods/veach/path.h"
#include "common/methods/veach/veach_chain.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

using veach::Path;
using veach::PathSpace;

SceneDesc withMirrorWall(SceneDesc desc) {
  BsdfDesc mirror;
  mirror.type = BsdfDesc::Type::Conductor;
  mirror.mirror = true;
  desc.bsdfs.push_back(mirror);
  for (MeshDesc& m : desc.meshes)
    if (m.name == "back") m.bsdf = int(desc.bsdfs.size()) - 1;
  return desc;
}

struct Counts {
  int proposed[veach::kNumKinds] = {}, irreversible[veach::kNumKinds] = {};
  int fromDeltaLight = 0;  // proposals (all kinds) from a path whose x_0 is a point or spot light
};

Counts proposeFromStartPaths(const SceneDesc& desc) {
  const auto scene = RenderScene::build(desc);
  const PathSpace space(*scene, 6);
  std::unique_ptr<veach::Mutation> moves[veach::kNumKinds] = {
      veach::makeBidirMutation(space), veach::makeLensPerturbation(space, 0.1, 2.0),
      veach::makeCausticPerturbation(space, 1e-4, 0.1), veach::makeMultiChainPerturbation(space, 0.1, 2.0, 1e-4, 0.1),
      veach::makeLensSubpathMutation(space), veach::makeDeepLensPerturbation(space, 0.1, 2.0, 1e-4, 0.1)};
  IntegratorSettings integrator;
  integrator.maxDepth = 6;
  Counts c;
  Pcg32 rng(17, 3);
  Path y;
  for (uint64_t i = 0; i < 3000; ++i) {
    IndependentSource src(123, i);
    const auto sp = veach::startPathFromSample(space, integrator, src, 0.5);
    if (!sp) continue;
    for (int kind = 0; kind < veach::kNumKinds; ++kind) {
      if (!moves[kind]->applicable(sp->path)) continue;
      for (int rep = 0; rep < 4; ++rep) {
        if (!moves[kind]->propose(sp->path, rng, y) || veach::samePath(sp->path, y)) continue;
        if (luminance(space.f(y, nullptr)) <= 0) continue;
        ++c.proposed[kind];
        const Path& x = sp->path;
        c.fromDeltaLight += veach::isDeltaPositionLight(x.v[0]);
        // The bidirectional mutation may delete a specular vertex of x, or re-aim a kept one (x_m traced
        // from again): its reverse would have to make x's specular scattering with both ends of the
        // changed part fixed, which has probability zero, so T(y -> x) = 0 there (the chain rejects such
        // y). Every other proposal must be reversible.
        bool deletedSpecular = false;
        if (kind == veach::kBidir) {
          int pre = 0, suf = 0;
          while (pre <= std::min(x.k(), y.k()) && x.v[pre].samePoint(y.v[pre])) ++pre;
          while (suf <= std::min(x.k(), y.k()) && x.v[x.k() - suf].samePoint(y.v[y.k() - suf])) ++suf;
          for (int j = std::max(0, pre - 1); j <= std::min(x.k(), x.k() - suf + 1); ++j) deletedSpecular |= x.v[j].specular;
        }
        const bool forward = moves[kind]->density(x, y) > 0;
        const bool backward = moves[kind]->density(y, x) > 0 && moves[kind]->applicable(y);
        if (!forward || (!backward && !deletedSpecular)) {
          ++c.irreversible[kind];
          if (getenv("VEACH_DEBUG")) {
            auto show = [](const Path& p) {
              std::string o;
              for (const auto& v : p.v)
                o += v.kind == veach::VertexKind::Light ? "L" : v.kind == veach::VertexKind::Camera ? "E" : (v.specular ? "S" : "D");
              return o;
            };
            std::printf("kind %d: x %s y %s fwd %d bwd %d\n", kind, show(x).c_str(), show(y).c_str(), int(forward), int(backward));
          }
        }
      }
    }
  }
  return c;
}

void expectReversible(const Counts& c, const char* scene) {
  for (int kind = 0; kind < veach::kNumKinds; ++kind) {
    std::printf("%s, %s: %d proposals with f > 0, %d irreversible\n", scene, veach::mutationKindNames()[kind].c_str(),
                c.proposed[kind], c.irreversible[kind]);
    EXPECT_GT(c.proposed[kind], 10) << scene << ": " << veach::mutationKindNames()[kind];
    EXPECT_EQ(c.irreversible[kind], 0) << scene << ": " << veach::mutationKindNames()[kind];
  }
}

TEST(VeachDensity, EveryProposalIsReversible) {
  expectReversible(proposeFromStartPaths(withMirrorWall(test::cornellBoxSpecular(16, 16))), "area light");
}

TEST(VeachDensity, EveryProposalIsReversibleWithPointAndSpotLights) {
  const Counts c = proposeFromStartPaths(withMirrorWall(test::cornellBoxSpecularPointSpot(16, 16)));
  expectReversible(c, "point + spot");
  int all = 0;
  for (int p : c.proposed) all += p;
  EXPECT_EQ(c.fromDeltaLight, all);
}

}  // namespace
}  // namespace mlt
