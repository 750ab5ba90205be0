// Path tracing with NEE and MIS (see path_tracer.h for the streams and conventions).
#include "common/integrators/path_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/core/sampling.h"
#include "common/integrators/bsdf_numbers.h"
#include "common/render/render_scene.h"

namespace mlt {

namespace {

inline float misWeight2(MisHeuristic h, float fPdf, float gPdf) {
  return h == MisHeuristic::Power ? powerHeuristic(fPdf, gPdf) : balanceHeuristic(fPdf, gPdf);
}

}  // namespace

Color PathTracer::Li(SampleSource& source, const Vec2* pixel, Vec2* pRaster) const {
  const RenderScene& scene = scene_;
  const Camera& camera = scene.camera();
  const LightSampler& lightSampler = scene.lightSampler();
  const int maxDepth = settings_.maxDepth, rrDepth = settings_.rrDepth;
  const MisHeuristic heuristic = settings_.heuristic;

  source.startStream(Stream::Camera);
  const Vec2 u = source.next2D();
  const Vec2 uLens = source.next2D();
  *pRaster = pixel ? *pixel + u : Vec2(u.x * float(camera.width()), u.y * float(camera.height()));
  Ray ray = camera.generateRay(*pRaster, uLens).ray;

  // Throughput: We cos / (pdfPos pdfDir) = 1 for the camera ray (see bdpt.cpp, generateCameraSubpath).
  Color L, beta(1.0f);
  float etaScale = 1;
  bool specular = true;  // the last direction was a camera ray or a delta lobe: no light sampling matched it
  float prevPdfW = 0;    // solid-angle density of the last BSDF-sampled direction
  Vec3 prevP;
  for (int bounce = 0;; ++bounce) {
    const int segments = bounce + 1;  // the ray being traced is segment number `segments`
    const std::optional<SurfaceHit> hit = scene.intersect(ray);
    if (!hit) {
      for (int i : scene.infiniteLights()) {
        const Light& light = scene.light(i);
        const Color Le = light.Le(ray.d);
        if (Le.isBlack()) continue;
        float w = 1;
        if (!specular) {
          const float lightPdf = lightSampler.pmf(i) *
                                 light.pdfLi(prevP, prevP + ray.d * (2 * scene.radius()), -ray.d, ray.d);
          w = misWeight2(heuristic, prevPdfW, lightPdf);
        }
        L += beta * Le * w;
      }
      break;
    }
    // Emission seen along the sampled direction.
    if (hit->light >= 0) {
      const Light& light = scene.light(hit->light);
      const Color Le = light.L(hit->p, hit->ng, hit->uv, -ray.d);
      if (!Le.isBlack()) {
        float w = 1;
        if (!specular) {
          const float lightPdf = lightSampler.pmf(hit->light) * light.pdfLi(prevP, hit->p, hit->ng, ray.d);
          w = misWeight2(heuristic, prevPdfW, lightPdf);
        }
        L += beta * Le * w;
      }
    }
    if (maxDepth >= 0 && segments >= maxDepth) break;

    const Bsdf& bsdf = scene.bsdf(hit->bsdf);
    const Frame frame(hit->ns);
    const Vec3 wo = -ray.d;
    const Vec3 woL = frame.toLocal(wo);
    const BsdfQuery query{hit->uv, TransportMode::Radiance};

    // Next-event estimation: a light in proportion to power, a point on it (Connect stream).
    if (!bsdf.isDelta()) {
      source.startStream(Stream::Connect);
      source.seek(connectNeeOffset(bounce));
      float pmf = 0;
      const int li = lightSampler.sample(source.next1D(), &pmf);
      const Vec2 uLight = source.next2D();
      if (li >= 0 && pmf > 0) {
        const Light& light = scene.light(li);
        const std::optional<LightLiSample> ls = light.sampleLiVisible(hit->p, hit->ng, uLight);
        if (ls && !ls->L.isBlack() && ls->pdfW > 0) {
          const Vec3 wiL = frame.toLocal(ls->wi);
          const Color f = bsdf.eval(woL, wiL, query) * std::fabs(wiL.z);
          if (!f.isBlack() && (ls->unoccluded || scene.visible(hit->p, hit->ng, ls->pLight, ls->nLight))) {
            const float lightPdf = pmf * ls->pdfW;
            float w = 1;
            if (!(ls->deltaPosition || light.deltaPosition() || light.deltaDirection()))
              w = misWeight2(heuristic, lightPdf, bsdf.pdf(woL, wiL, query));
            L += beta * f * ls->L * (w / lightPdf);
          }
        }
      }
    }

    // BSDF sampling (Camera stream, the vertex's block).
    source.startStream(Stream::Camera);
    const BsdfNumbers u = readBsdfNumbers(source, kCameraDims + bounce * kBsdfDims, bsdf.reads());
    const std::optional<BsdfSample> bs = bsdf.sample(woL, u.uComponent, u.uDir, query);
    if (!bs || bs->f.isBlack() || !(bs->pdfW > 0)) break;
    beta *= bs->f * (std::fabs(bs->wi.z) / bs->pdfW);
    etaScale *= bs->eta * bs->eta;
    specular = bs->delta;
    prevPdfW = bs->pdfW;
    prevP = hit->p;
    if (rrDepth >= 0 && segments >= rrDepth) {
      const float q = std::min(1.0f, beta.maxComponent() * etaScale);
      if (!(source.next1D() < q)) break;  // block entry [3]
      beta *= 1 / q;
    }
    if (beta.isBlack()) break;
    const Vec3 wi = frame.toWorld(bs->wi);
    ray.o = offsetRayOrigin(hit->p, hit->ng, wi);
    ray.d = wi;
    ray.tMin = 0;
    ray.tMax = std::numeric_limits<float>::infinity();
  }
  return L;
}

void PathTracer::evaluate(SampleSource& source, const Vec2* pixel, PathContribution& out) const {
  out.clear();
  const Color L = Li(source, pixel, &out.cameraRaster);
  if (!L.isBlack()) out.splats.push_back(Splat{out.cameraRaster, L, -1, -1});
}

}  // namespace mlt
