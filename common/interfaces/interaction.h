// Rays and surface hits: what the Embree wrapper returns and what BSDFs, lights and integrators consume.
#pragma once
#include <cstdint>
#include <limits>

#include "common/core/vec.h"

namespace mlt {

struct Ray {
  Vec3 o, d;          // d need not be unit for shadow rays; camera/BSDF rays are unit
  float tMin = 0.0f;
  float tMax = std::numeric_limits<float>::infinity();
  Vec3 at(float t) const { return o + d * t; }
};

struct SurfaceHit {
  Vec3 p;             // world position
  Vec3 ng;            // geometric normal (unit, front side = counter-clockwise winding)
  Vec3 ns;            // shading normal (unit; interpolated vertex normal, or ng), same side as ng
  Vec2 uv;
  float t = 0.0f;     // ray parameter
  uint32_t meshId = 0, primId = 0;
  int bsdf = -1;      // index into RenderScene::bsdf()
  int light = -1;     // index into RenderScene::lights() if the mesh emits, else -1
  Frame shading() const { return Frame(ns); }
};

// Offset a ray origin off a surface along the geometric normal to avoid self-intersection; `w` is the
// direction the new ray will travel.
inline Vec3 offsetRayOrigin(const Vec3& p, const Vec3& ng, const Vec3& w) {
  const float scale = 1e-4f * fmaxNum(1.0f, fmaxNum(std::fabs(p.x), fmaxNum(std::fabs(p.y), std::fabs(p.z))));
  return p + (dot(w, ng) > 0 ? ng : -ng) * scale;
}

}  // namespace mlt
