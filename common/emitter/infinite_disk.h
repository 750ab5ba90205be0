// What the lights at infinity (directional, constant environment) share. They need the scene's bounding
// sphere (center c, radius R), given by preprocess():
//  - sampleLi puts pLight at ref + wi * 2R with nLight = -wi, so a shadow ray to it leaves the scene;
//  - sampleLe starts rays on a disk of radius R perpendicular to the travel direction, a distance R
//    "behind" the scene center (pbrt-v3): pdfPos = 1 / (pi R^2).
#pragma once
#include <optional>

#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"
#include "common/core/vec.h"

namespace mlt {

// Origin of an emitted ray travelling along w (unit) through the disk of radius R about c.
inline Vec3 diskOrigin(const Vec3& c, float R, const Vec3& w, Vec2 uPos) {
  const Frame f(w);
  const Vec2 d = sampleConcentricDisk(uPos);
  return c + (f.s * d.x + f.t * d.y) * R - w * R;
}

// Inverse of diskOrigin: the uPos of an origin o for travel direction w, or nullopt if o is not on the
// disk. Jacobian (per unit area of the disk): 1 / (pi R^2).
inline std::optional<Vec2> invertDiskOrigin(const Vec3& c, float R, const Vec3& w, const Vec3& o) {
  const Frame f(w);
  const Vec3 d = (o - c + w * R) / R;
  const Vec2 q(dot(d, f.s), dot(d, f.t));
  if (!(std::fabs(dot(d, f.n)) <= 1e-3f) || !(q.x * q.x + q.y * q.y <= 1 + 2e-4f)) return std::nullopt;
  return invertConcentricDisk(q);
}

}  // namespace mlt
