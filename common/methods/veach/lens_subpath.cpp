// Veach's lens subpath mutation (Veach 1997, sec. 11.4.4): the eye subpath E S* D of x (m =
// eyeChainEnd(x), x_{m-1} non-specular) is replaced by a fresh one: a film position uniform over the
// film, a lens point uniform over the lens, then Dirac lobes chosen with their own probabilities through
// purely specular surfaces until the first surface with a non-Dirac component, which is connected to the
// kept x_{m-1}. It keeps the chain moving over the whole image (the perturbations only move it locally).
//
// The new subpath is independent of x's, so in the canonical measure (path.h)
//     T(x -> y) = p_lens * prod_{i = m}^{k_y - 1} eyeStep(y, i)
// (p_lens = 1 / lens area; eyeStep from the lens: pdfDir converted to area; after a specular vertex: the
// lobe probability), for every y whose first m vertices are x's and whose eye subpath has that form.
// The move applies only where x's own eye subpath has it (purely Dirac chain, a non-Dirac end), so that
// the reverse move exists.
#include "common/methods/veach/mutations.h"
#include "common/render/render_scene.h"

namespace mlt::veach {

namespace {

// The eye subpath from index m on is E S* D with S purely Dirac surfaces and D not.
bool freshEyeForm(const Path& x, int m) {
  const int k = x.k();
  if (m < 1 || m >= k || x.v[m - 1].specular) return false;
  if (x.v[m].specular || x.v[m].kind != VertexKind::Surface || x.v[m].bsdf->isDelta()) return false;
  for (int i = m + 1; i < k; ++i)
    if (!x.v[i].specular || !x.v[i].bsdf->isDelta()) return false;
  return true;
}

class LensSubpathMutation final : public Mutation {
 public:
  explicit LensSubpathMutation(const PathSpace& space) : space_(space) {}

  bool applicable(const Path& x) const override { return freshEyeForm(x, eyeChainEnd(x)); }

  bool propose(const Path& x, Pcg32& rng, Path& y) const override {
    const int m = eyeChainEnd(x);
    const Camera& cam = space_.scene().camera();
    thread_local std::vector<PathVertex> eye;  // scratch: no allocation per proposal once grown
    eye.clear();
    const Vec2 raster(rng.uniform() * float(cam.width()), rng.uniform() * float(cam.height()));
    const Vec2 uLens = rng.uniform2();
    Vec3 dir;
    eye.push_back(space_.cameraVertex(raster, uLens, &dir));
    for (;;) {
      if (m + int(eye.size()) > space_.maxEdges()) return false;  // y would exceed the depth limit
      const PathVertex& prev = eye.back();
      std::optional<PathVertex> hit = space_.trace(prev.p, prev.kind == VertexKind::Camera ? Vec3() : prev.ng, dir);
      if (!hit) return false;
      if (!hit->bsdf->isDelta()) {
        hit->specular = false;
        eye.push_back(*hit);
        break;
      }
      const std::optional<BsdfSample> bs = sampleDirection(*hit, prev, TransportMode::Radiance, rng, &dir);
      if (!bs || !bs->delta) return false;
      hit->specular = true;
      eye.push_back(*hit);
    }
    y.v.assign(x.v.begin(), x.v.begin() + m);
    y.v.insert(y.v.end(), eye.rbegin(), eye.rend());
    y.uLens = uLens;
    return y.k() <= space_.maxEdges();
  }

  double density(const Path& x, const Path& y) const override {
    const int m = eyeChainEnd(x);
    if (!freshEyeForm(x, m) || eyeChainEnd(y) != m || !freshEyeForm(y, m)) return 0;
    for (int i = 0; i < m; ++i)
      if (!x.v[i].samePoint(y.v[i])) return 0;
    double T = space_.lensDensity();
    for (int i = y.k() - 1; i >= m && T > 0; --i) T *= space_.eyeStep(y, i);
    return T;
  }

 private:
  const PathSpace& space_;
};

}  // namespace

std::unique_ptr<Mutation> makeLensSubpathMutation(const PathSpace& space) {
  return std::make_unique<LensSubpathMutation>(space);
}

}  // namespace mlt::veach
