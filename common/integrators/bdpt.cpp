// BDPT: subpath generation, connection and MIS weights (see bdpt.h for conventions and streams).
#include "common/integrators/bdpt.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/core/sampling.h"
#include "common/integrators/bsdf_numbers.h"
#include "common/render/render_scene.h"

namespace mlt {

namespace {

// Continues a subpath from path[0] (camera or light vertex, already filled) along `ray`, whose direction
// was sampled with solid-angle density pdfW, writing path[1..]. Bounce i (the i-th surface vertex) reads
// its kBsdfDims block at blockBase + i * kBsdfDims of the current stream. Returns the vertices added.
int randomWalk(const RenderScene& scene, SampleSource& source, Ray ray, Color beta, float pdfW, int maxVertices,
               TransportMode mode, int rrDepth, int blockBase, Vertex* path) {
  if (maxVertices <= 1) return 0;
  const bool importance = mode == TransportMode::Importance;
  Color rrBeta(1.0f);  // throughput relative to the subpath's start, for roulette
  float etaScale = 1;
  int added = 0;
  for (int bounce = 0;; ++bounce) {
    Vertex& prev = path[bounce];
    Vertex& v = path[bounce + 1];
    const std::optional<SurfaceHit> hit = scene.intersect(ray);
    if (!hit) {
      // Escaped: camera subpaths end on an infinite-light vertex when the scene has infinite lights.
      if (!importance && !scene.infiniteLights().empty()) {
        v = Vertex();
        v.type = VertexType::InfiniteLight;
        v.p = ray.o + ray.d * (2 * scene.radius() + length(ray.o - scene.center()));
        v.ng = v.ns = -ray.d;
        v.wo = -ray.d;
        v.beta = beta;
        v.pdfFwd = pdfW;  // solid angle (pbrt's convention for infinite lights)
        ++added;
      }
      break;
    }
    v = Vertex();
    v.type = VertexType::Surface;
    v.importance = importance;
    v.p = hit->p;
    v.ng = hit->ng;
    v.ns = hit->ns;
    v.uv = hit->uv;
    v.wo = -ray.d;
    v.beta = beta;
    v.bsdf = &scene.bsdf(hit->bsdf);
    if (hit->light >= 0) {
      v.lightIndex = hit->light;
      v.light = &scene.light(hit->light);
    }
    v.pdfFwd = prev.convertDensity(pdfW, v);
    ++added;
    if (added + 1 >= maxVertices) break;

    // Sample the next direction (the vertex's fixed block: component, direction, roulette).
    const BsdfNumbers u = readBsdfNumbers(source, blockBase + bounce * kBsdfDims, v.bsdf->reads());
    const Frame frame(v.ns);
    const Vec3 woL = frame.toLocal(v.wo);
    const std::optional<BsdfSample> bs = v.bsdf->sample(woL, u.uComponent, u.uDir, BsdfQuery{v.uv, mode});
    if (!bs || bs->f.isBlack() || !(bs->pdfW > 0)) break;
    const Vec3 wi = frame.toWorld(bs->wi);
    Color scatter = bs->f * (std::fabs(bs->wi.z) / bs->pdfW);
    if (importance) scatter *= shadingNormalCorrection(v.wo, wi, v.ng, v.ns);
    else etaScale *= bs->eta * bs->eta;
    beta *= scatter;
    rrBeta *= scatter;
    float pdfFwdW = bs->pdfW, pdfRevW = bs->pdfRevW;
    if (bs->delta) {
      v.delta = true;
      pdfFwdW = pdfRevW = 0;  // remapped to 1 in the ratio chain; delta vertices are skipped there
    }
    prev.pdfRev = v.convertDensity(pdfRevW, prev);
    // Russian roulette once the subpath has rrDepth segments (bounce + 1 so far).
    if (rrDepth >= 0 && bounce + 1 >= rrDepth) {
      const float q = std::min(1.0f, rrBeta.maxComponent() * etaScale);
      if (!(source.next1D() < q)) break;  // block entry [3]
      beta *= 1 / q;
      rrBeta *= 1 / q;
    }
    if (beta.isBlack()) break;
    ray.o = offsetRayOrigin(v.p, v.ng, wi);
    ray.d = wi;
    ray.tMin = 0;
    ray.tMax = std::numeric_limits<float>::infinity();
    pdfW = pdfFwdW;
  }
  return added;
}

// The raster position of Camera [0,1] = u: within `pixel` if one is given, else anywhere on the film.
Vec2 filmPosition(const Camera& camera, const Vec2* pixel, Vec2 u) {
  return pixel ? *pixel + u : Vec2(u.x * float(camera.width()), u.y * float(camera.height()));
}

// Geometry term with visibility, shading normals for the cosines (pbrt-v3's G).
float G(const RenderScene& scene, const Vertex& v0, const Vertex& v1) {
  Vec3 d = v0.p - v1.p;
  const float d2 = lengthSquared(d);
  if (!(d2 > 0)) return 0;
  float g = 1 / d2;
  d = d * std::sqrt(g);
  if (v0.isOnSurface()) g *= absDot(v0.ns, d);
  if (v1.isOnSurface()) g *= absDot(v1.ns, d);
  if (g == 0) return 0;
  return scene.visible(v0.p, v0.ng, v1.p, v1.ng) ? g : 0.0f;
}

}  // namespace

int generateCameraSubpath(const RenderScene& scene, SampleSource& source, const Vec2* pixel, int maxVertices,
                          int rrDepth, Vertex* path, Vec2* pRaster) {
  if (maxVertices <= 0) return 0;
  const Camera& camera = scene.camera();
  source.startStream(Stream::Camera);
  const Vec2 u = source.next2D();
  const Vec2 uLens = source.next2D();
  *pRaster = filmPosition(camera, pixel, u);
  const CameraRay cr = camera.generateRay(*pRaster, uLens);
  const float pdfPos = cr.pdfPos, pdfDir = cr.pdfDir;  // = camera.pdfWe(cr.ray) up to rounding
  Vertex& c = path[0];
  c = Vertex();
  c.type = VertexType::Camera;
  c.p = cr.ray.o;
  c.ns = cr.n;
  // We cos / (pdfPos pdfDir) = 1 for the film-normalized importance of camera.h (and also for a ray
  // restricted to one pixel, where both We and the raster density scale by the pixel count).
  c.beta = Color(1.0f);
  c.pdfFwd = pdfPos;
  if (!(pdfDir > 0)) return 1;
  return 1 + randomWalk(scene, source, cr.ray, c.beta, pdfDir, maxVertices, TransportMode::Radiance, rrDepth,
                        kCameraDims, path);
}

int generateLightSubpath(const RenderScene& scene, SampleSource& source, int maxVertices, int rrDepth, Vertex* path) {
  if (maxVertices <= 0) return 0;
  source.startStream(Stream::Light);
  float pmf = 0;
  const int index = scene.lightSampler().sample(source.next1D(), &pmf);
  if (index < 0 || !(pmf > 0)) return 0;
  const Light& light = scene.light(index);
  const Vec2 uPos = source.next2D();
  const Vec2 uDir = source.next2D();
  const std::optional<LightLeSample> le = light.sampleLe(uPos, uDir);
  if (!le || le->L.isBlack() || !(le->pdfPos > 0) || !(le->pdfDir > 0)) return 0;
  Vertex& v = path[0];
  v = Vertex();
  v.type = VertexType::Light;
  v.light = &light;
  v.lightIndex = index;
  v.p = le->ray.o;
  v.ng = v.ns = le->nLight;
  v.uv = le->uv;  // a textured area light's Le() at this point (s = 1, t = 1)
  // The light vertex's own weight: 1 / (pmf pdfPos); its emitted radiance enters through Le() (s = 1
  // connections to the camera) or through the first segment's throughput below.
  v.beta = Color(1 / (pmf * le->pdfPos));
  const bool infiniteLike = v.isInfiniteLight();
  // Origin density: area (pmf pdfPos); infinite lights: the solid-angle density of the direction;
  // directional lights: pmf alone (delta direction).
  if (light.infinite()) v.pdfFwd = infiniteLightDensity(scene, le->ray.o, -le->ray.d);
  else if (light.deltaDirection()) v.pdfFwd = pmf;
  else v.pdfFwd = pmf * le->pdfPos;
  const bool hasNormal = le->nLight.x != 0 || le->nLight.y != 0 || le->nLight.z != 0;
  const float cosLight = (hasNormal && !infiniteLike) ? absDot(le->nLight, le->ray.d) : 1.0f;
  const Color beta = le->L * (cosLight / (pmf * le->pdfPos * le->pdfDir));
  const int n = 1 + randomWalk(scene, source, le->ray, beta, le->pdfDir, maxVertices, TransportMode::Importance,
                               rrDepth, kLightDims, path);
  if (infiniteLike && n > 1) {
    // pbrt-v3: the vertex after an infinite (or directional) light has the planar density of the disk.
    path[1].pdfFwd = le->pdfPos;
    if (path[1].isOnSurface()) path[1].pdfFwd *= absDot(le->ray.d, path[1].ng);
  }
  return n;
}

Color connectBdpt(const RenderScene& scene, SampleSource& source, Vertex* light, int s, Vertex* camera, int t,
                  Vertex* sampled, Vec2* pRaster) {
  if (t > 1 && s != 0 && camera[t - 1].type == VertexType::InfiniteLight) return {};
  Color L;
  if (s == 0) {
    // The camera subpath's last vertex is on an emitter.
    const Vertex& pt = camera[t - 1];
    if (pt.isLight()) L = pt.beta * pt.Le(scene, camera[t - 2]);
  } else if (t == 1) {
    // Connect the light subpath's last vertex to a lens point (light tracing, Veach sec. 10.2).
    const Vertex& qs = light[s - 1];
    if (!qs.isConnectible() || qs.isInfiniteLight()) return {};
    if (s == 1 && !qs.isOnSurface()) return {};  // a point light is never seen by the lens
    source.startStream(Stream::Camera);
    source.seek(2);
    const std::optional<CameraWiSample> cs = scene.camera().sampleWi(qs.p, source.next2D());
    if (!cs || !(cs->pdfW > 0) || cs->We.isBlack()) return {};
    Vertex& c = *sampled;
    c = Vertex();
    c.type = VertexType::Camera;
    c.p = cs->pLens;
    c.ns = cs->nLens;
    c.beta = cs->We / cs->pdfW;
    if (s == 1) {
      L = qs.beta * qs.Le(scene, c) * c.beta * absDot(cs->wi, qs.ng);
    } else {
      L = qs.beta * qs.f(c) * c.beta;
      if (qs.isOnSurface()) L *= absDot(cs->wi, qs.ns);
    }
    if (L.isBlack() || !scene.visible(qs.p, qs.ng, c.p, Vec3())) return {};
    *pRaster = cs->pRaster;
  } else if (s == 1) {
    // Resample the light vertex by next-event estimation from the camera subpath's last vertex.
    const Vertex& pt = camera[t - 1];
    if (!pt.isConnectible()) return {};
    source.startStream(Stream::Connect);
    source.seek(connectNeeOffset(t - 2));
    float pmf = 0;
    const int index = scene.lightSampler().sample(source.next1D(), &pmf);
    if (index < 0 || !(pmf > 0)) return {};
    const Light& l = scene.light(index);
    const std::optional<LightLiSample> ls = l.sampleLiVisible(pt.p, pt.ng, source.next2D());
    if (!ls || ls->L.isBlack() || !(ls->pdfW > 0)) return {};
    Vertex& q = *sampled;
    q = Vertex();
    q.type = VertexType::Light;
    q.light = &l;
    q.lightIndex = index;
    q.p = ls->pLight;
    q.ng = q.ns = ls->nLight;
    q.uv = ls->uv;
    q.beta = ls->L / (ls->pdfW * pmf);
    q.pdfFwd = q.pdfLightOrigin(scene, pt);
    L = pt.beta * pt.f(q) * q.beta;
    if (pt.isOnSurface()) L *= absDot(ls->wi, pt.ns);
    if (L.isBlack() || !(ls->unoccluded || scene.visible(pt.p, pt.ng, q.p, q.ng))) return {};
  } else {
    const Vertex& qs = light[s - 1];
    const Vertex& pt = camera[t - 1];
    if (!qs.isConnectible() || !pt.isConnectible()) return {};
    L = qs.beta * qs.f(pt) * pt.f(qs) * pt.beta;
    if (L.isBlack()) return {};
    L *= G(scene, qs, pt);
  }
  return L;
}

float misWeight(const RenderScene& scene, Vertex* light, int s, Vertex* camera, int t, const Vertex& sampled,
                MisHeuristic heuristic) {
  if (s + t == 2) return (s == 0) ? 1.0f : 0.0f;  // (1,1) is lt's alone; bdpt covers it with (0,2)
  Vertex* qs = s > 0 ? &light[s - 1] : nullptr;
  Vertex* pt = t > 0 ? &camera[t - 1] : nullptr;
  Vertex* qsMinus = s > 1 ? &light[s - 2] : nullptr;
  Vertex* ptMinus = t > 1 ? &camera[t - 2] : nullptr;

  // Temporary changes (pbrt-v3 MISWeight), undone before returning.
  Vertex savedEndpoint;
  Vertex* replaced = nullptr;
  if (s == 1) replaced = qs;
  else if (t == 1) replaced = pt;
  if (replaced) {
    savedEndpoint = *replaced;
    *replaced = sampled;
  }
  const bool ptDelta = pt ? pt->delta : false, qsDelta = qs ? qs->delta : false;
  if (pt) pt->delta = false;
  if (qs) qs->delta = false;
  const float ptRev = pt ? pt->pdfRev : 0, ptMinusRev = ptMinus ? ptMinus->pdfRev : 0;
  const float qsRev = qs ? qs->pdfRev : 0, qsMinusRev = qsMinus ? qsMinus->pdfRev : 0;
  if (pt) pt->pdfRev = s > 0 ? qs->pdf(scene, qsMinus, *pt) : pt->pdfLightOrigin(scene, *ptMinus);
  if (ptMinus) ptMinus->pdfRev = s > 0 ? pt->pdf(scene, qs, *ptMinus) : pt->pdfLight(scene, *ptMinus);
  if (qs) qs->pdfRev = pt->pdf(scene, ptMinus, *qs);
  if (qsMinus) qsMinus->pdfRev = qs->pdf(scene, pt, *qsMinus);

  // The strategy s = 1 finds the light's point y by sampleLi from its neighbour x, the strategies s >= 2 by
  // sampleLe: the ratio chain below carries sampleLe's density of y (pdfLightOrigin) for both, and k, the
  // first's density over the second's (Light::pdfLiOverPdfPos; exactly 1 unless they differ: a sphere
  // light's cone), corrects the strategy s = 1: its ratio r_1 = k r_1' when it is not the strategy
  // evaluated, and every r_i = r_i' / k when it is (p_1 = k p_1').
  float k = 1;
  {
    const Vertex* y = s > 0 ? &light[0] : (t >= 2 ? &camera[t - 1] : nullptr);
    const Vertex* x = s > 1 ? &light[1] : s == 1 ? pt : ptMinus;
    if (y && x && y->light && y->light->liDensityDiffers() && y->isOnSurface()) k = y->light->pdfLiOverPdfPos(x->p, y->p, y->ng);
  }

  // Veach eq. 10.9 by ratios r_i = p_i / p_s of neighbouring strategies (pbrt-v3 sec. 16.3.4);
  // the power heuristic (beta = 2) sums r_i^2. A zero density stands for a delta and is remapped to 1.
  auto remap0 = [](float f) { return f != 0 ? f : 1.0f; };
  const bool power = heuristic == MisHeuristic::Power;
  float sumRi = 0, ri = 1;
  const auto add = [&](float r, bool strategyS1) {
    if (strategyS1) r *= k;
    sumRi += power ? r * r : r;
  };
  for (int i = t - 1; i > 0; --i) {
    ri *= remap0(camera[i].pdfRev) / remap0(camera[i].pdfFwd);
    // Strategy (s + t - i, i); (1, 1) is not a bdpt strategy.
    if (!camera[i].delta && !camera[i - 1].delta && !(i == 1 && s + t - i == 1)) add(ri, s + t - i == 1);
  }
  ri = 1;
  for (int i = s - 1; i >= 0; --i) {
    ri *= remap0(light[i].pdfRev) / remap0(light[i].pdfFwd);
    const bool deltaLightVertex = i > 0 ? light[i - 1].delta : light[0].isDeltaLight();
    // Strategy (i, s + t - i); (1, 1) excluded as above.
    if (!light[i].delta && !deltaLightVertex && !(i == 1 && s + t - i == 1)) add(ri, i == 1);
  }
  if (s == 1 && k != 1) sumRi /= power ? k * k : k;

  if (qsMinus) qsMinus->pdfRev = qsMinusRev;
  if (qs) qs->pdfRev = qsRev;
  if (ptMinus) ptMinus->pdfRev = ptMinusRev;
  if (pt) pt->pdfRev = ptRev;
  if (qs) qs->delta = qsDelta;
  if (pt) pt->delta = ptDelta;
  if (replaced) *replaced = savedEndpoint;
  return 1 / (1 + sumRi);
}

TechniqueSample evaluateTechnique(const RenderScene& scene, SampleSource& source, int s, int t,
                                  MisHeuristic heuristic, BdptWorkspace& ws, const Vec2* pixel,
                                  Vertex* sampledOut) {
  TechniqueSample r;
  if (t < 1 || s < 0 || s + t < 2) return r;
  ws.reserve(t, std::max(s, 1));
  if (t == 1) {
    // Light tracing: connectBdpt samples the lens point toward the light subpath, and misWeight puts that
    // vertex in camera[0]'s place, so a camera ray would go unused. Its numbers are still read, as
    // generateCameraSubpath reads them (a chain's draws stay those of every technique), but no ray is
    // made: ~40 ns of a Markov chain's light-tracing mutations.
    const Camera& camera = scene.camera();
    source.startStream(Stream::Camera);
    const Vec2 u = source.next2D();
    source.next2D();  // the lens numbers, read again by connectBdpt
    r.pRaster = filmPosition(camera, pixel, u);
    ws.camera[0] = Vertex();
    ws.camera[0].type = VertexType::Camera;
  } else if (generateCameraSubpath(scene, source, pixel, t, -1, ws.camera.data(), &r.pRaster) != t) {
    return r;
  }
  // s = 1 resamples its light vertex in connectBdpt: no light subpath to trace.
  if (s > 1 && generateLightSubpath(scene, source, s, -1, ws.light.data()) != s) return r;
  Vertex sampled;
  Vec2 pRaster = r.pRaster;
  const Color C = connectBdpt(scene, source, ws.light.data(), s, ws.camera.data(), t, &sampled, &pRaster);
  if (C.isBlack() || !C.isFinite()) return r;
  r.C = C;
  r.pRaster = pRaster;
  r.weight = misWeight(scene, ws.light.data(), s, ws.camera.data(), t, sampled, heuristic);
  if (sampledOut) *sampledOut = sampled;
  return r;
}

Color evaluateLength(const RenderScene& scene, SampleSource& source, int k, MisHeuristic heuristic,
                     BdptWorkspace& ws) {
  if (k < 1) return {};
  ws.reserve(k + 1, k);
  Vec2 pRaster;
  const int nc = generateCameraSubpath(scene, source, nullptr, k + 1, -1, ws.camera.data(), &pRaster);
  const int nl = k >= 2 ? generateLightSubpath(scene, source, k, -1, ws.light.data()) : 0;
  Color sum;
  for (int s = 0; s <= k; ++s) {
    const int t = k + 1 - s;
    if (s + t == 2 && s > 0) continue;  // (1, 1): lt's alone, weight 0 (misWeight)
    if ((t >= 2 && nc < t) || (s >= 2 && nl < s)) continue;  // a subpath ended early
    Vertex sampled;
    Vec2 p = pRaster;
    const Color C = connectBdpt(scene, source, ws.light.data(), s, ws.camera.data(), t, &sampled, &p);
    if (C.isBlack() || !C.isFinite()) continue;
    const float w = misWeight(scene, ws.light.data(), s, ws.camera.data(), t, sampled, heuristic);
    sum += C * w;
  }
  return sum;
}

}  // namespace mlt
