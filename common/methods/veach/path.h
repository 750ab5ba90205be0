// Veach's path space (Veach 1997, ch. 8 and 11): a light transport path as a list of vertices
//     x = (x_0, ..., x_k),   x_0 on a light, x_k on the lens,
// its measurement contribution f(x) and the local sampling densities from which the mutations of
// mutations.h build their transition densities T(x -> y).
//
// ---- The measure (specular vertices) ------------------------------------------------------------------
// Away from Dirac BSDFs, f and every density are in the area-product measure (eq. 8.4):
//     f(x) = Le(x_0 -> x_1) G(x_0, x_1) prod_{i=1}^{k-1} [ rho(x_i) G(x_i, x_{i+1}) ] We(x_k -> x_{k-1}),
//     G(a, b) = |cos_a| |cos_b| / |a - b|^2   (geometric normals; cosines only at surface points, the lens
//               counts the camera's forward axis as its normal),
//     rho(x_i) = fs(x_{i-1} -> x_i -> x_{i+1}) |ns . w_{i-1}| / |ng . w_{i-1}|  (radiance-form BSDF with
//               shading normals, Veach eq. 5.19; w_{i-1} = unit direction toward x_{i-1}).
// A specular vertex s (its scattering used a Dirac lobe) fixes the position of one neighbour given the
// other. The canonical ("eye-free") convention used throughout: the Dirac distribution of s is taken
// against the area of its neighbour on the LIGHT side. Then f's coefficient replaces
//     rho(s) G(s, x_light-side)   by   F(s) = f_delta |ns . w_light-side|   (the lobe's throughput weight),
// i.e. the edge from s toward the light contributes no geometric factor. This is exactly the measure in
// which a camera subpath (bdpt's t vertices) has density prod pdfA with a specular vertex contributing its
// lobe probability alone, so f(x) / p_eye(x) is bdpt's unweighted C(0, t) (checked in veach_path_test).
// Densities of vertices generated from the light side through a specular chain are in the other ("light-
// free") convention: the chain's light-side end v and the specular vertex after it are free. Conservation
// of etendue along the chain converts them (lightChainToCanonical). With refraction, the conversion
// assumes the chain's two ends lie in the same medium (true for closed dielectric objects).
//
// ---- Delta-position lights (point, spot) --------------------------------------------------------------
// x_0 on such a light is a point of counting measure: its density is the light's selection probability
// (lightStep(x, 0) = pmf, pdfPos = 1, as bdpt's pdfLightOrigin), Le(x_0 -> x_1) is the intensity I(w) and
// G(x_0, x_1) has no cosine at x_0. The eye side never reaches it (eyeStep(x, 0) = 0, as bdpt's s = 0
// strategies), so no move generates, moves or perturbs it except the bidirectional mutation's light side,
// which re-samples it (and its emitted direction by the light's own sampleLe: pdfDir). A specular run
// x_1 .. x_r next to such a light cannot use the canonical convention (the delta against x_0's area: x_0
// has none); that run alone stays in the light-free one (x_1 free, its eye-side end a determined), in
// which every path with it is generated (from the light: bidir's light side, the caustic perturbation)
// or kept (the other moves). f then carries G(x_0, x_1) instead of G(a, s_1) (f divides the canonical
// coefficient by the etendue factor), and lightChainToCanonical is 1 for that run. The path L E (the
// light seen directly) has measure zero and f = 0 (the bidirectional mutation can propose it).
//
// Supported: area, point and spot lights; pinhole and thin-lens cameras; every BSDF (Dirac lobes are
// recognised by re-sampling them, see specularLobe). Directional and environment lights are rejected at
// construction, naming the light (a delta direction or a position at infinity: no area or point density).
#pragma once
#include <optional>
#include <vector>

#include "common/core/color.h"
#include "common/core/rng.h"
#include "common/core/vec.h"
#include "common/interfaces/bsdf.h"

namespace mlt {

class RenderScene;
class Light;

namespace veach {

enum class VertexKind : uint8_t { Light, Surface, Camera };

struct PathVertex {
  VertexKind kind = VertexKind::Surface;
  bool specular = false;  // Surface: scatters through a Dirac lobe in this path (S); else D (or L / E)
  Vec3 p, ng, ns;         // Camera: ns = ng = forward axis
  Vec2 uv;
  const Bsdf* bsdf = nullptr;    // Surface
  const Light* light = nullptr;  // Light (and Surface vertices lying on an emitter)
  int lightIndex = -1;
  bool samePoint(const PathVertex& o) const { return p.x == o.p.x && p.y == o.p.y && p.z == o.p.z; }
};

struct Path {
  std::vector<PathVertex> v;  // v[0] light ... v[k] camera
  Vec2 uLens;                 // the lens sample of v[k] (thin lens: regenerates rays from the same lens point)
  int k() const { return int(v.size()) - 1; }  // number of edges
  const PathVertex& camera() const { return v.back(); }
};

// A lobe of a Dirac BSDF that maps wo to wi: its throughput weight (f such that f |cos wi| / pdf is the
// throughput), its probability of being chosen (pdf) and whether it transmits.
struct SpecularLobe {
  Color f;
  float pdf = 0;
  bool transmit = false;
};
// Finds the Dirac lobe of `bsdf` taking wo to wi (local shading frame) by sampling every lobe
// (uComponent at the ends of [0,1) and between); nullopt if none does (within 1e-3 in cos).
std::optional<SpecularLobe> specularLobe(const Bsdf& bsdf, const Vec3& woL, const Vec3& wiL, const BsdfQuery& q);

// Path-space functions of one scene and depth limit.
class PathSpace {
 public:
  // maxDepth: at most this many edges (-1: kUnlimitedEdges); minEdges: at least this many (separateDirect:
  // kDirectMaxSegments + 1, the shorter paths are the direct pass's; f is zero on them). Throws for
  // unsupported lights.
  // withoutLightViews: f is also zero on the paths E S* L (every vertex between the light and the lens
  // specular: the light seen directly or through mirrors and glass), which the light-view pass renders
  // (light_view.h).
  PathSpace(const RenderScene& scene, int maxDepth, int minEdges = 1, bool withoutLightViews = false);
  const RenderScene& scene() const { return scene_; }
  int maxEdges() const { return maxEdges_; }
  int minEdges() const { return minEdges_; }
  bool withoutLightViews() const { return withoutLightViews_; }
  // Whether x is E S* L (x.v[1..k-1] all specular; vacuously for the light seen directly).
  static bool isLightView(const Path& x);
  static constexpr int kUnlimitedEdges = 32;

  // f(x) in the canonical measure, with visibility; *pRaster: where the path lands. Zero (and no raster)
  // when invalid: length outside [minEdges, maxEdges], a light view (withoutLightViews), a vertex of the wrong kind, a specular vertex without a matching lobe, a
  // blocked edge, the lens edge outside the film.
  // `seen`, if given, is a path whose f is not zero (the chain's current state), so every edge of it was
  // tested unoccluded: an edge of x with the same two ends (bit for bit the same positions and normals
  // passed to the test) at the same index counted from the light or from the lens is not tested again.
  // The test is a function of those arguments alone, so f is bit for bit the same with or without `seen`;
  // a mutation keeps most of a path's edges, so this saves most of its shadow rays.
  Color f(const Path& x, Vec2* pRaster, const Path* seen = nullptr) const;

  // ---- local densities (canonical measure, see above) ----
  // Density of generating x.v[i] from the eye side, from x.v[i+1] (given x.v[i+2]): from the camera by a
  // film position uniform over the film and the kept lens point; after a specular vertex its lobe
  // probability; else the BSDF's solid-angle density converted to area at x.v[i].
  double eyeStep(const Path& x, int i) const;
  // Density of the camera vertex itself when the eye side starts afresh (1 / lens area; 1 for a pinhole).
  double lensDensity() const { return lensDensity_; }
  // Density of generating x.v[i] from the light side: i = 0 the light point (light choice x area),
  // i = 1 the emitted direction, else BSDF sampling at x.v[i-1] (importance transport; after a specular
  // vertex its lobe probability, in the light-free convention: see lightChainToCanonical).
  double lightStep(const Path& x, int i) const;
  // Raster position (pixels) as the camera sees direction camera -> x.v[k-1]; false if off the film.
  bool raster(const Path& x, Vec2* pRaster) const;
  // |ng . w| at a vertex (1 where there is no surface), w unit.
  static float cosAt(const PathVertex& v, const Vec3& w);

  // ---- tracing ----
  // Closest hit as a Surface vertex (bsdf, light handles), or nullopt.
  std::optional<PathVertex> trace(const Vec3& from, const Vec3& fromNg, const Vec3& dir) const;
  // Turns a Surface vertex lying on an emitter into the path's light vertex x_0; false if it does not
  // emit toward `toward`.
  bool makeLightVertex(PathVertex& v) const;
  // Lens edge: a camera ray through pRaster from the lens point of uLens.
  PathVertex cameraVertex(Vec2 pRaster, Vec2 uLens, Vec3* dir) const;

 private:
  const RenderScene& scene_;
  int maxEdges_;
  int minEdges_;
  bool withoutLightViews_;
  double lensDensity_ = 0;  // the camera's pdfPos (a constant of the camera)
};

// x_0 on a point or spot light.
bool isDeltaPositionLight(const PathVertex& v);

// Geometric term with geometric normals, no visibility.
float geometry(const PathVertex& a, const PathVertex& b);

// The specular run x.v[r0..r1] (r0 <= r1, all specular; v = x.v[r0-1] and a = x.v[r1+1] not) generated
// from the light side has light-free density; times this factor it is in the canonical measure:
//     G(a, s_1) / G(v, s_m) * prod_i |ns . w_eye| |ng . w_light| / (|ng . w_eye| |ns . w_light|),
// s_1 = x.v[r1], s_m = x.v[r0]. Etendue n^2 |cos| dA dw is conserved along a specular chain (equal media
// at both ends), so G(a, s_1) dA(a) dA(s_1) = G(v, s_m) dA(v) dA(s_m); each vertex
// scattering about its shading normal ns while areas use ng adds the product (measured: without it the
// caustic under a smooth-shaded glass sphere came out 25% dark). 1 for the run next to a delta-position
// light (r0 = 1), which stays light-free (see above).
double lightChainToCanonical(const Path& x, int r0, int r1);

}  // namespace veach
}  // namespace mlt
