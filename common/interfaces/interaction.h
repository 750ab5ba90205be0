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

// How far a ray leaving a surface point p must start from it to clear the surface's float error: 1e-4 of
// p's largest coordinate, at least 1e-4. offsetRayOrigin moves by it along the normal; rays that start at
// p itself (a light's emitted ray, a cone-sampled light ray) use it as tMin.
inline float rayOffsetScale(const Vec3& p) {
  return 1e-4f * fmaxNum(1.0f, fmaxNum(std::fabs(p.x), fmaxNum(std::fabs(p.y), std::fabs(p.z))));
}

// Offset a ray origin off a surface along the geometric normal to avoid self-intersection; `w` is the
// direction the new ray will travel.
inline Vec3 offsetRayOrigin(const Vec3& p, const Vec3& ng, const Vec3& w) {
  return p + (dot(w, ng) > 0 ? ng : -ng) * rayOffsetScale(p);
}

}  // namespace mlt
