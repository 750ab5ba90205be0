// Path inversion for a technique change (see path_inversion.h).
#include "common/methods/rjmlt/path_inversion.h"

#include <algorithm>
#include <cmath>

#include "common/core/sampling_inverse.h"
#include "common/methods/mmlt/mmlt_method.h"
#include "common/render/render_scene.h"

namespace mlt {

namespace {

InverseGamma drawGamma(Pcg32& rng) {
  InverseGamma g;
  g.pick = rng.uniform();
  g.fill = rng.uniform2();
  return g;
}

// Solid angle at a -> the measure of vertex b (area, or solid angle at infinity): bdpt's convertDensity.
double toMeasureOf(const Vertex& a, const Vertex& b) { return a.convertDensity(1.0f, b); }

Vec3 unitTo(const Vertex& from, const Vertex& to) { return normalize(to.p - from.p); }

// The index of the light at the path's end, or -1 if it cannot be told (see path_inversion.h).
int lightIndexOf(const RenderScene& scene, const Vertex& v) {
  if (v.lightIndex >= 0) {
    const Light& l = scene.light(v.lightIndex);
    if (l.infinite() && scene.infiniteLights().size() != 1) return -1;  // f sums them; which is ambiguous
    return v.lightIndex;
  }
  if (v.type == VertexType::InfiniteLight && scene.infiniteLights().size() == 1) return scene.infiniteLights()[0];
  return -1;
}

// The BSDF sample at v from prev toward next, inverted into the block at `base` of `vals`; returns the
// Jacobian in the measure of next, or 0 if the BSDF cannot produce that direction.
double invertBounce(const Vertex* prev, bool prevIsEndpoint, const Vertex& v, const Vertex& next, TransportMode mode,
                    Pcg32& rng, float* block) {
  if (v.type != VertexType::Surface || !v.bsdf || !prev) return 0;
  const Frame frame(v.ns);
  // The forward walk traces from v.p offset along ng (offsetRayOrigin): aim from there, so that the
  // re-traced ray lands on next.p itself rather than 1e-4 beside it (which grazing bounces amplify).
  // The Jacobian converts to area from that same origin: it is the density of the forward map itself.
  Vec3 wi = unitTo(v, next);
  double toNext = 1;  // solid angle -> measure of next (a vertex at infinity stays in solid angle)
  if (!next.isInfiniteLight()) {
    const Vec3 d = next.p - offsetRayOrigin(v.p, v.ng, wi);
    const double d2 = lengthSquared(d);
    if (!(d2 > 0)) return 0;
    wi = d / float(std::sqrt(d2));
    toNext = (next.isOnSurface() ? absDot(next.ng, wi) : 1.0) / d2;
  }
  // Likewise the ray that reached v left prev from its offset origin, unless prev is the subpath's
  // endpoint (lens or light), whose rays start on the point itself.
  Vec3 wo = unitTo(v, *prev);
  if (!prevIsEndpoint && !prev->isInfiniteLight()) wo = normalize(offsetRayOrigin(prev->p, prev->ng, -wo) - v.p);
  const Vec3 woL = frame.toLocal(wo), wiL = frame.toLocal(wi);
  const std::optional<BsdfSampleInverse> inv = v.bsdf->invertSample(woL, wiL, drawGamma(rng), BsdfQuery{v.uv, mode});
  if (!inv || !(inv->jacobian > 0)) return 0;
  block[0] = inv->uComponent;
  block[1] = inv->uDir.x;
  block[2] = inv->uDir.y;
  return double(inv->jacobian) * toNext;
}

}  // namespace

bool traceTechnique(const RenderScene& scene, SampleSource& source, int s, int t, MisHeuristic heuristic,
                    BdptWorkspace& ws, MmltPath* out) {
  Vertex sampled;
  const TechniqueSample ts = evaluateTechnique(scene, source, s, t, heuristic, ws, nullptr, &sampled);
  if (ts.C.isBlack()) return false;
  const int k = s + t - 1;
  out->s = s;
  out->t = t;
  out->C = ts.C;
  out->weight = ts.weight;
  out->pRaster = ts.pRaster;
  out->z.resize(k + 1);
  for (int i = 0; i < t; ++i) out->z[i] = (t == 1 && i == 0) ? sampled : ws.camera[i];
  for (int j = 0; j < s; ++j) out->z[k - j] = (s == 1 && j == 0) ? sampled : ws.light[j];
  return true;
}

void appendMmltSplat(const MmltPath& p, PathContribution& out) {
  const float w = p.weight * float(mmltTechniqueCount(p.length()));
  if (!(w > 0)) return;
  Splat sp;
  sp.pRaster = p.pRaster;
  sp.L = p.C * w;
  sp.s = static_cast<int16_t>(p.s);
  sp.t = static_cast<int16_t>(p.t);
  out.splats.push_back(sp);
}

int mmltTechniqueOf(SampleSource& source, int k) {
  const int n = mmltTechniqueCount(k);
  if (k <= 1) return 0;
  source.startStream(Stream::Connect);
  source.seek(kConnectTechniqueDim);
  return std::min(n - 1, static_cast<int>(source.next1D() * float(n)));  // as MethodTarget::evaluate
}

int mmltFootprint(int k, Stream stream) {
  switch (stream) {
    case Stream::Camera: return kCameraDims + std::max(0, k - 1) * kBsdfDims;  // t <= k + 1: blocks 0..k-2
    case Stream::Light: return kLightDims + std::max(0, k - 2) * kBsdfDims;    // s <= k: blocks 0..k-3
    case Stream::Connect: return connectNeeOffset(std::max(0, k - 1));         // NEE blocks of t - 2 <= k - 2
  }
  return 0;
}

std::optional<PathInverse> invertTechnique(const RenderScene& scene, const std::vector<Vertex>& z, int s, int t,
                                           Pcg32& rng) {
  const int k = static_cast<int>(z.size()) - 1;
  if (k < 1 || s < 0 || t < 1 || s + t != k + 1 || (k > 1 ? false : s != 0)) return std::nullopt;
  // Sec. 6.1: the whole footprint starts uniform; the coordinates technique (s, t) reads are overwritten.
  std::vector<float> vals[kNumStreams];
  for (int st = 0; st < kNumStreams; ++st) {
    vals[st].resize(mmltFootprint(k, static_cast<Stream>(st)));
    for (float& v : vals[st]) v = rng.uniform();
  }
  std::vector<float>& cam = vals[int(Stream::Camera)];
  std::vector<float>& lig = vals[int(Stream::Light)];
  std::vector<float>& con = vals[int(Stream::Connect)];
  double J = 1;

  // MMLT's technique choice: s = floor(u n), the interval [s/n, (s+1)/n) (eq. 40), Jacobian 1/n.
  if (k > 1) {
    const int n = mmltTechniqueCount(k);
    float u = invertInterval(double(s) / n, double(s + 1) / n, rng.uniform());
    while (u > 0 && static_cast<int>(u * float(n)) > s) u = std::nextafter(u, 0.0f);
    while (static_cast<int>(u * float(n)) < s) u = std::nextafter(u, 1.0f);
    con[kConnectTechniqueDim] = u;
    J /= n;
  }

  // ---- camera subpath z[0..t-1] ----
  const Camera& camera = scene.camera();
  if (t >= 2) {
    Ray ray;
    ray.o = z[0].p;
    ray.d = unitTo(z[0], z[1]);
    const std::optional<CameraRayInverse> ci = camera.invertGenerateRay(ray, drawGamma(rng));
    if (!ci) return std::nullopt;
    const float W = float(camera.width()), H = float(camera.height());
    cam[0] = clampPrimary(ci->pRaster.x / W);
    cam[1] = clampPrimary(ci->pRaster.y / H);
    cam[2] = ci->lens.u.x;
    cam[3] = ci->lens.u.y;
    // raster numbers per steradian = jacobianRaster / (W H) = pdfDir; lens: pdfPos.
    J *= double(ci->lens.jacobian) * (double(ci->jacobianRaster) / (double(W) * H)) * toMeasureOf(z[0], z[1]);
    for (int m = 1; m <= t - 2; ++m) {
      const double j = invertBounce(&z[m - 1], m == 1, z[m], z[m + 1], TransportMode::Radiance, rng,
                                    &cam[kCameraDims + (m - 1) * kBsdfDims]);
      if (!(j > 0)) return std::nullopt;
      J *= j;
    }
  } else {
    // t = 1: the lens point of the connection, sampled from z[1] (Camera [2,3], as connectBdpt reads it).
    const std::optional<Inverse2D> li = camera.invertSampleWi(z[1].p, z[0].p, drawGamma(rng));
    if (!li) return std::nullopt;
    cam[2] = li->u.x;
    cam[3] = li->u.y;
    J *= li->jacobian;
  }

  // ---- light subpath z[k], z[k-1], ..., z[t] ----
  const Vertex& end = z[k];
  if (s == 0) {
    // The camera walk hits the emitter: it must be hittable (not a delta light) and unambiguous.
    if (!end.isLight() || end.isDeltaLight() || (end.isInfiniteLight() && lightIndexOf(scene, end) < 0))
      return std::nullopt;
  } else {
    const int li = lightIndexOf(scene, end);
    if (li < 0) return std::nullopt;
    const Light& light = scene.light(li);
    const std::optional<float> uLight = scene.lightSampler().invertSample(li, rng.uniform());
    if (!uLight) return std::nullopt;
    J *= scene.lightSampler().pmf(li);
    const Vertex& next = z[k - 1];
    if (s == 1) {
      // Next-event estimation from z[k-1]: Connect NEE block of bounce t - 2.
      const int base = connectNeeOffset(t - 2);
      const std::optional<Inverse2D> ls = light.invertSampleLi(next.p, end.p, end.ng, drawGamma(rng));
      if (!ls) return std::nullopt;
      con[base] = *uLight;
      con[base + 1] = ls->u.x;
      con[base + 2] = ls->u.y;
      J *= ls->jacobian;  // pdfA (infinite lights: pdfW of the direction, the measure of a vertex at infinity)
    } else {
      const Vec3 w = unitTo(end, next);  // travel direction of the emitted ray
      Vec3 pLight = end.p, nLight = end.ng;
      const bool atInfinity = light.infinite() || light.deltaDirection();
      if (atInfinity) {
        // The emitted ray starts on the disk of radius R, a distance R behind the center (infinite_disk.h).
        const Vec3 c = scene.center() - w * scene.radius();
        pLight = next.p - w * dot(next.p - c, w);
        nLight = w;
      }
      const std::optional<LightLeInverse> le = light.invertSampleLe(pLight, nLight, w, drawGamma(rng));
      if (!le) return std::nullopt;
      lig[0] = *uLight;
      lig[1] = le->pos.u.x;
      lig[2] = le->pos.u.y;
      lig[3] = le->dir.u.x;
      lig[4] = le->dir.u.y;
      if (atInfinity)  // the light vertex in solid angle, the next one by the disk's planar density
        J *= double(le->dir.jacobian) * le->pos.jacobian * (next.isOnSurface() ? absDot(next.ng, w) : 1.0f);
      else
        J *= double(le->pos.jacobian) * le->dir.jacobian * toMeasureOf(end, next);
      for (int j = 1; j <= s - 2; ++j) {
        const double jb = invertBounce(&z[k - j + 1], j == 1, z[k - j], z[k - j - 1], TransportMode::Importance, rng,
                                       &lig[kLightDims + (j - 1) * kBsdfDims]);
        if (!(jb > 0)) return std::nullopt;
        J *= jb;
      }
    }
  }
  if (!(J > 0) || !std::isfinite(J)) return std::nullopt;

  PathInverse out;
  out.jacobian = J;
  for (int st = 0; st < kNumStreams; ++st)
    for (int i = 0; i < static_cast<int>(vals[st].size()); ++i) out.writes.push_back({st, i, vals[st][i]});
  return out;
}

bool connectsAtDelta(const std::vector<Vertex>& z, int s, int t) {
  if (s == 0) return false;
  auto delta = [](const Vertex& v) { return v.type == VertexType::Surface && v.bsdf && v.bsdf->isDelta(); };
  const int k = static_cast<int>(z.size()) - 1;
  return delta(z[t - 1]) || delta(z[k - s + 1]);
}

bool samePath(const RenderScene& scene, const std::vector<Vertex>& a, const std::vector<Vertex>& b, float tolerance) {
  if (a.size() != b.size()) return false;
  const float tolP = tolerance * std::fmax(1.0f, scene.radius());
  for (size_t i = 0; i < a.size(); ++i) {
    const bool infA = a[i].isInfiniteLight(), infB = b[i].isInfiniteLight();
    if (infA != infB) return false;
    if (infA) {
      if (i == 0 || length(unitTo(a[i - 1], a[i]) - unitTo(b[i - 1], b[i])) > tolerance) return false;
    } else if (length(a[i].p - b[i].p) > tolP) {
      return false;
    }
  }
  return true;
}

}  // namespace mlt
