// Veach's path space: f(x) and local densities in the canonical measure (see path.h).
#include "common/methods/veach/path.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "common/render/render_scene.h"

namespace mlt::veach {

namespace {

Vec3 unitToward(const Vec3& from, const Vec3& to, float* d2) {
  const Vec3 w = to - from;
  *d2 = lengthSquared(w);
  return *d2 > 0 ? w / std::sqrt(*d2) : Vec3();
}

// The normal RenderScene::visible gets for a vertex: none at the lens (path.h), else the geometric one.
Vec3 visibilityNormal(const PathVertex& v) { return v.kind == VertexKind::Camera ? Vec3() : v.ng; }

bool sameBits(const Vec3& a, const Vec3& b) {
  return std::bit_cast<uint32_t>(a.x) == std::bit_cast<uint32_t>(b.x) &&
         std::bit_cast<uint32_t>(a.y) == std::bit_cast<uint32_t>(b.y) &&
         std::bit_cast<uint32_t>(a.z) == std::bit_cast<uint32_t>(b.z);
}

// Whether the visibility test of x's edge (x_i, x_{i+1}) has the same arguments as that of seen's edge
// (seen_j, seen_{j+1}).
bool sameVisibilityTest(const Path& x, int i, const Path& seen, int j) {
  if (j < 0 || j + 1 > seen.k()) return false;
  for (int e = 0; e < 2; ++e) {
    const PathVertex &a = x.v[i + e], &b = seen.v[j + e];
    if (!sameBits(a.p, b.p) || !sameBits(visibilityNormal(a), visibilityNormal(b))) return false;
  }
  return true;
}

}  // namespace

std::optional<SpecularLobe> specularLobe(const Bsdf& bsdf, const Vec3& woL, const Vec3& wiL, const BsdfQuery& q) {
  // Every Dirac BSDF here picks its lobe by comparing uComponent with cumulative lobe probabilities, so
  // these values reach each lobe of non-negligible probability.
  static constexpr float kU[] = {0.0f, kOneMinusEpsilon, 0.5f, 0.25f, 0.75f, 0.05f, 0.95f};
  for (float u : kU) {
    const std::optional<BsdfSample> bs = bsdf.sample(woL, u, Vec2(0.5f, 0.5f), q);
    if (!bs || !bs->delta || !(bs->pdfW > 0)) continue;
    if (dot(bs->wi, wiL) > 0.999f) return SpecularLobe{bs->f, bs->pdfW, woL.z * bs->wi.z < 0};
  }
  return std::nullopt;
}

float PathSpace::cosAt(const PathVertex& v, const Vec3& w) {
  if (v.kind == VertexKind::Camera) return absDot(v.ns, w);
  if (v.ng.x == 0 && v.ng.y == 0 && v.ng.z == 0) return 1.0f;
  return absDot(v.ng, w);
}

float geometry(const PathVertex& a, const PathVertex& b) {
  float d2;
  const Vec3 w = unitToward(a.p, b.p, &d2);
  if (!(d2 > 0)) return 0;
  return PathSpace::cosAt(a, w) * PathSpace::cosAt(b, w) / d2;
}

bool isDeltaPositionLight(const PathVertex& v) {
  return v.kind == VertexKind::Light && v.light && v.light->deltaPosition();
}

namespace {

// The etendue conversion factor of lightChainToCanonical (path.h), whatever the chain's light end.
double etendueFactor(const Path& x, int r0, int r1) {
  const auto& v = x.v;
  const double gv = geometry(v[r0 - 1], v[r0]);
  if (!(gv > 0)) return 0;
  double factor = geometry(v[r1 + 1], v[r1]) / gv;
  for (int i = r0; i <= r1; ++i) {
    const PathVertex& s = v[i];
    float d2;
    const Vec3 we = unitToward(s.p, v[i + 1].p, &d2), wl = unitToward(s.p, v[i - 1].p, &d2);
    const double den = double(absDot(s.ng, we)) * absDot(s.ns, wl);
    if (!(den > 0)) return 0;
    factor *= double(absDot(s.ns, we)) * absDot(s.ng, wl) / den;
  }
  return factor;
}

// The run of specular vertices x_1 .. x_r1 next to a delta-position light (path.h): r1, or 0 if there is none.
int deltaLightRunEnd(const Path& x) {
  if (x.k() < 2 || !isDeltaPositionLight(x.v[0]) || !x.v[1].specular) return 0;
  int r1 = 1;
  while (r1 + 1 < x.k() && x.v[r1 + 1].specular) ++r1;
  return r1;
}

// Emission from x_0 toward x_1: area lights their radiance Le(x_0 -> x_1); delta-position lights their
// intensity I(x_0 -> x_1), read as sampleLi's I / d^2 at x_1 times d^2 (the position is the light's own,
// so sampleLi reads no random numbers).
Color emitted(const PathVertex& light, const PathVertex& next) {
  float d2;
  const Vec3 w = unitToward(light.p, next.p, &d2);
  if (!light.light->deltaPosition()) return light.light->L(light.p, light.ng, light.uv, w);
  const std::optional<LightLiSample> ls = light.light->sampleLi(next.p, Vec2(0.5f, 0.5f));
  if (!ls || !(d2 > 0)) return {};
  return ls->L * d2;
}

}  // namespace

double lightChainToCanonical(const Path& x, int r0, int r1) {
  if (r0 == 1 && isDeltaPositionLight(x.v[0])) return 1.0;  // that run stays light-free (path.h)
  return etendueFactor(x, r0, r1);
}

PathSpace::PathSpace(const RenderScene& scene, int maxDepth, int minEdges, bool withoutLightViews)
    : scene_(scene),
      maxEdges_(maxDepth < 0 ? kUnlimitedEdges : maxDepth),
      minEdges_(std::max(minEdges, 1)),
      withoutLightViews_(withoutLightViews) {
  for (size_t i = 0; i < scene.lights().size(); ++i) {
    const Light& l = *scene.lights()[i];
    const char* type = l.deltaDirection() ? "a directional light"
                       : l.infinite()     ? "an environment (infinite) light"
                                          : nullptr;
    if (type)
      throw std::invalid_argument(fmt::format("veach-mlt: light {} of the scene is {}; veach-mlt supports area, "
                                              "point and spot lights only", i, type));
  }
  const Camera& cam = scene.camera();
  const CameraRay cr = cam.generateRay(Vec2(0.5f * float(cam.width()), 0.5f * float(cam.height())), Vec2(0.5f, 0.5f));
  float pdfPos = 0, pdfDir = 0;
  cam.pdfWe(cr.ray, &pdfPos, &pdfDir);
  lensDensity_ = pdfPos;
}

bool PathSpace::isLightView(const Path& x) {
  for (int i = 1; i < x.k(); ++i)
    if (!x.v[i].specular) return false;
  return true;
}

Color PathSpace::f(const Path& x, Vec2* pRaster, const Path* seen) const {
  const int k = x.k();
  if (k < minEdges_ || k > maxEdges_) return {};
  if (withoutLightViews_ && isLightView(x)) return {};
  const auto& v = x.v;
  if (v[0].kind != VertexKind::Light || !v[0].light || v[k].kind != VertexKind::Camera) return {};
  for (int i = 1; i < k; ++i)
    if (v[i].kind != VertexKind::Surface || !v[i].bsdf) return {};
  // A point or spot light seen directly by the lens is a path of measure zero (a point on the film, as
  // bdpt's s = 1, t = 1 skips it); its f would be an atom the chain cannot weigh against area densities.
  if (k == 1 && isDeltaPositionLight(v[0])) return {};
  float d2;
  // Le(x_0 -> x_1) (a delta-position light: its intensity, the position being a point of counting measure)
  Color F = emitted(v[0], v[1]);
  if (F.isBlack()) return {};
  // rho(x_i): radiance-form BSDF factors (path.h).
  for (int i = 1; i < k; ++i) {
    const PathVertex& s = v[i];
    const Vec3 wo = unitToward(s.p, v[i + 1].p, &d2), wi = unitToward(s.p, v[i - 1].p, &d2);
    const Frame frame(s.ns);
    const BsdfQuery q{s.uv, TransportMode::Radiance};
    if (s.specular) {
      const std::optional<SpecularLobe> lobe = specularLobe(*s.bsdf, frame.toLocal(wo), frame.toLocal(wi), q);
      if (!lobe) return {};
      F *= lobe->f * absDot(s.ns, wi);
    } else {
      const float cosG = absDot(s.ng, wi);
      if (!(cosG > 0)) return {};
      F *= s.bsdf->eval(frame.toLocal(wo), frame.toLocal(wi), q) * (absDot(s.ns, wi) / cosG);
    }
    if (F.isBlack()) return {};
  }
  // Edges: G, except from a specular vertex toward its light-side neighbour (canonical measure).
  for (int i = 0; i < k; ++i) {
    const PathVertex& a = v[i];
    const PathVertex& b = v[i + 1];
    if (!(b.kind == VertexKind::Surface && b.specular)) F *= geometry(a, b);
    if (F.isBlack()) return {};
    // An edge `seen` has (same index from the light, or from the lens) passed this very test.
    if (seen && (sameVisibilityTest(x, i, *seen, i) || sameVisibilityTest(x, i, *seen, i + seen->k() - k))) continue;
    if (!scene_.visible(a.p, visibilityNormal(a), b.p, visibilityNormal(b))) return {};
  }
  Ray r;
  r.o = v[k].p;
  r.d = unitToward(v[k].p, v[k - 1].p, &d2);
  Vec2 raster;
  const Color We = scene_.camera().We(r, &raster);
  if (We.isBlack()) return {};
  F *= We;
  // A specular run next to a delta-position light is in the light-free measure (path.h): f carries
  // G(x_0, x_1) and not G(a, s_1), i.e. the canonical coefficient over the etendue factor.
  if (const int r1 = deltaLightRunEnd(x); r1 > 0) {
    const double factor = etendueFactor(x, 1, r1);
    if (!(factor > 0)) return {};
    F *= float(1.0 / factor);
  }
  if (!F.isFinite()) return {};
  if (pRaster) *pRaster = raster;
  return F;
}

bool PathSpace::raster(const Path& x, Vec2* pRaster) const {
  const int k = x.k();
  if (k < 1) return false;
  float d2;
  Ray r;
  r.o = x.v[k].p;
  r.d = unitToward(x.v[k].p, x.v[k - 1].p, &d2);
  return !scene_.camera().We(r, pRaster).isBlack();
}

double PathSpace::eyeStep(const Path& x, int i) const {
  const PathVertex& from = x.v[i + 1];
  const PathVertex& to = x.v[i];
  float d2;
  const Vec3 w = unitToward(from.p, to.p, &d2);
  if (!(d2 > 0) || isDeltaPositionLight(to)) return 0;  // a delta-position light is never hit
  if (from.kind == VertexKind::Camera) {
    Ray r;
    r.o = from.p;
    r.d = w;
    float pdfPos = 0, pdfDir = 0;
    scene_.camera().pdfWe(r, &pdfPos, &pdfDir);
    return double(pdfDir) * cosAt(to, w) / d2;
  }
  if (from.kind != VertexKind::Surface || i + 2 >= int(x.v.size())) return 0;
  const Vec3 wo = unitToward(from.p, x.v[i + 2].p, &d2);
  const Frame frame(from.ns);
  const BsdfQuery q{from.uv, TransportMode::Radiance};
  if (from.specular) {
    const std::optional<SpecularLobe> lobe = specularLobe(*from.bsdf, frame.toLocal(wo), frame.toLocal(w), q);
    return lobe ? double(lobe->pdf) : 0.0;
  }
  float d2to;
  unitToward(from.p, to.p, &d2to);
  return double(from.bsdf->pdf(frame.toLocal(wo), frame.toLocal(w), q)) * cosAt(to, w) / d2to;
}

double PathSpace::lightStep(const Path& x, int i) const {
  const auto& v = x.v;
  if (i == 0) {
    if (v[0].kind != VertexKind::Light || !v[0].light || v.size() < 2) return 0;
    float d2, pdfPos = 0, pdfDir = 0;
    v[0].light->pdfLe(v[0].p, v[0].ng, unitToward(v[0].p, v[1].p, &d2), &pdfPos, &pdfDir);
    return double(scene_.lightSampler().pmf(v[0].lightIndex)) * pdfPos;
  }
  float d2;
  const Vec3 w = unitToward(v[i - 1].p, v[i].p, &d2);
  if (!(d2 > 0)) return 0;
  if (i == 1) {
    float pdfPos = 0, pdfDir = 0;
    v[0].light->pdfLe(v[0].p, v[0].ng, w, &pdfPos, &pdfDir);
    return double(pdfDir) * cosAt(v[1], w) / d2;
  }
  const PathVertex& from = v[i - 1];
  if (from.kind != VertexKind::Surface) return 0;
  float d2p;
  const Vec3 wo = unitToward(from.p, v[i - 2].p, &d2p);
  const Frame frame(from.ns);
  const BsdfQuery q{from.uv, TransportMode::Importance};
  if (from.specular) {
    const std::optional<SpecularLobe> lobe = specularLobe(*from.bsdf, frame.toLocal(wo), frame.toLocal(w), q);
    return lobe ? double(lobe->pdf) : 0.0;
  }
  return double(from.bsdf->pdf(frame.toLocal(wo), frame.toLocal(w), q)) * cosAt(v[i], w) / d2;
}

std::optional<PathVertex> PathSpace::trace(const Vec3& from, const Vec3& fromNg, const Vec3& dir) const {
  // The ray starts exactly at `from` and skips its own surface by tMin, so the hit lies on the line
  // from + t dir: the perturbations measure their steps back from vertex positions, and an origin offset
  // along the normal (1e-4 scene units) would move the line by more than caustic steps of 1e-4 rad.
  Ray r;
  r.o = from;
  r.d = dir;
  if (fromNg.x != 0 || fromNg.y != 0 || fromNg.z != 0) {
    const float scale = fmaxNum(1.0f, fmaxNum(std::fabs(from.x), fmaxNum(std::fabs(from.y), std::fabs(from.z))));
    r.tMin = 1e-4f * scale / fmaxNum(absDot(fromNg, dir), 0.05f);
  }
  const std::optional<SurfaceHit> hit = scene_.intersect(r);
  if (!hit) return std::nullopt;
  PathVertex v;
  v.kind = VertexKind::Surface;
  v.p = hit->p;
  v.ng = hit->ng;
  v.ns = hit->ns;
  v.uv = hit->uv;
  v.bsdf = &scene_.bsdf(hit->bsdf);
  if (hit->light >= 0) {
    v.lightIndex = hit->light;
    v.light = &scene_.light(hit->light);
  }
  return v;
}

bool PathSpace::makeLightVertex(PathVertex& v) const {
  if (!v.light) return false;
  v.kind = VertexKind::Light;
  v.specular = false;
  v.ns = v.ng;
  return true;
}

PathVertex PathSpace::cameraVertex(Vec2 pRaster, Vec2 uLens, Vec3* dir) const {
  const CameraRay cr = scene_.camera().generateRay(pRaster, uLens);
  PathVertex c;
  c.kind = VertexKind::Camera;
  c.p = cr.ray.o;
  c.ng = c.ns = cr.n;
  *dir = cr.ray.d;
  return c;
}

}  // namespace mlt::veach
