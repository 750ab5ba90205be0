// Affine transforms as 4x4 matrices in double (scene files compose many of them; rounding stays small).
#pragma once
#include <array>
#include <cmath>

#include "common/core/vec.h"

namespace mlt {

struct Transform {
  // Row-major: m[row][col]; points are column vectors: p' = m * (p, 1).
  std::array<std::array<double, 4>, 4> m{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};

  static Transform identity() { return {}; }
  static Transform translate(const Vec3& d);
  static Transform scale(const Vec3& s);
  static Transform rotate(const Vec3& axis, double angleDegrees);
  // Mitsuba's lookat: camera at `origin` looking at `target`; +z forward, `up` gives +y.
  static Transform lookAt(const Vec3& origin, const Vec3& target, const Vec3& up);

  Transform operator*(const Transform& o) const;  // (this * o)(p) = this(o(p))
  Transform inverse() const;                      // throws std::runtime_error if singular
  Transform transpose() const;
  bool isFinite() const;
  double determinant3x3() const;                  // < 0: the transform flips orientation
  // A rotation, translation, uniform scale or mirror (what a camera's to_world may be): the images of
  // the axes are non-zero, of equal length and orthogonal, to a relative tolerance of 1e-4.
  bool isSimilarity() const;

  Vec3 point(const Vec3& p) const;
  Vec3 vector(const Vec3& v) const;
  Vec3 normal(const Vec3& n) const;  // uses the inverse transpose; not normalized
};

}  // namespace mlt
