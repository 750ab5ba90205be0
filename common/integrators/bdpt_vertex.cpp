// Vertex densities and values for BDPT (see bdpt.h for the measure conventions).
#include <cmath>

#include "common/core/sampling.h"
#include "common/integrators/bdpt.h"
#include "common/render/render_scene.h"

namespace mlt {

// Solid-angle density with which the infinite lights, chosen by the light sampler, produce direction
// wToLight (pbrt-v3 InfiniteLightDensity). Summed over every infinite light, because an escaped camera
// ray collects the radiance of all of them.
float infiniteLightDensity(const RenderScene& scene, const Vec3& ref, const Vec3& wToLight) {
  float pdf = 0;
  const float R2 = 2 * scene.radius();
  for (int i : scene.infiniteLights()) {
    const Light& l = scene.light(i);
    pdf += scene.lightSampler().pmf(i) * l.pdfLi(ref, ref + wToLight * R2, -wToLight, wToLight);
  }
  return pdf;
}

bool Vertex::isInfiniteLight() const {
  return type == VertexType::InfiniteLight ||
         (type == VertexType::Light && light && (light->infinite() || light->deltaDirection()));
}

bool Vertex::isDeltaLight() const {
  return (type == VertexType::Light) && light && (light->deltaPosition() || light->deltaDirection());
}

bool Vertex::isConnectible() const {
  switch (type) {
    case VertexType::Camera: return true;
    case VertexType::Light: return !light->deltaDirection();
    case VertexType::Surface: return !bsdf->isDelta();
    case VertexType::InfiniteLight: return false;
  }
  return false;
}

Color Vertex::f(const Vertex& next) const {
  Vec3 wi = next.p - p;
  const float d2 = lengthSquared(wi);
  if (!(d2 > 0)) return {};
  wi = wi / std::sqrt(d2);
  const Frame frame(ns);
  BsdfQuery q{uv, importance ? TransportMode::Importance : TransportMode::Radiance};
  Color value = bsdf->eval(frame.toLocal(wo), frame.toLocal(wi), q);
  if (importance) value *= shadingNormalCorrection(wo, wi, ng, ns);
  return value;
}

float Vertex::convertDensity(float pdfW, const Vertex& next) const {
  if (next.isInfiniteLight()) return pdfW;
  const Vec3 w = next.p - p;
  const float d2 = lengthSquared(w);
  if (!(d2 > 0)) return 0;
  const float invD2 = 1 / d2;
  if (next.isOnSurface()) pdfW *= absDot(next.ng, w * std::sqrt(invD2));
  return pdfW * invD2;
}

float Vertex::pdf(const RenderScene& scene, const Vertex* prev, const Vertex& next) const {
  if (type == VertexType::Light) return pdfLight(scene, next);
  Vec3 wn = next.p - p;
  if (!(lengthSquared(wn) > 0)) return 0;
  wn = normalize(wn);
  float pdfW = 0;
  if (type == VertexType::Camera) {
    Ray r;
    r.o = p;
    r.d = wn;
    float pdfPos = 0;
    scene.camera().pdfWe(r, &pdfPos, &pdfW);
  } else if (type == VertexType::Surface) {
    if (!prev) return 0;
    Vec3 wp = prev->p - p;
    if (!(lengthSquared(wp) > 0)) return 0;
    wp = normalize(wp);
    const Frame frame(ns);
    BsdfQuery q{uv, importance ? TransportMode::Importance : TransportMode::Radiance};
    pdfW = bsdf->pdf(frame.toLocal(wp), frame.toLocal(wn), q);
  } else {
    return 0;
  }
  return convertDensity(pdfW, next);
}

float Vertex::pdfLight(const RenderScene& scene, const Vertex& v) const {
  Vec3 w = v.p - p;
  const float d2 = lengthSquared(w);
  if (!(d2 > 0)) return 0;
  const float invD2 = 1 / d2;
  w = w * std::sqrt(invD2);
  float pdf;
  if (isInfiniteLight()) {
    // Planar density of the ray origin on the disk of radius R perpendicular to the direction.
    const float R = scene.radius();
    pdf = 1 / (kPi * R * R);
  } else {
    float pdfPos = 0, pdfDir = 0;
    light->pdfLe(p, ng, w, &pdfPos, &pdfDir);
    pdf = pdfDir * invD2;
  }
  if (v.isOnSurface()) pdf *= absDot(v.ng, w);
  return pdf;
}

float Vertex::pdfLightOrigin(const RenderScene& scene, const Vertex& v) const {
  Vec3 w = v.p - p;
  if (!(lengthSquared(w) > 0)) return 0;
  w = normalize(w);
  if (type == VertexType::InfiniteLight || (light && light->infinite()))
    return infiniteLightDensity(scene, v.p, -w);
  const float pmf = scene.lightSampler().pmf(lightIndex);
  if (light->deltaDirection()) return pmf;  // directional: the direction is a delta, density 1
  float pdfPos = 0, pdfDir = 0;
  light->pdfLe(p, ng, w, &pdfPos, &pdfDir);
  return pdfPos * pmf;
}

Color Vertex::Le(const RenderScene& scene, const Vertex& v) const {
  if (!isLight()) return {};
  Vec3 w = v.p - p;
  if (!(lengthSquared(w) > 0)) return {};
  w = normalize(w);
  if (isInfiniteLight()) {
    Color L;
    for (int i : scene.infiniteLights()) L += scene.light(i).Le(-w);
    return L;
  }
  return light->L(p, ng, uv, w);
}

void BdptWorkspace::reserve(int cameraVertices, int lightVertices) {
  if (int(camera.size()) < cameraVertices) camera.resize(cameraVertices);
  if (int(light.size()) < lightVertices) light.resize(lightVertices);
}

}  // namespace mlt
