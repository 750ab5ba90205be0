// Inverses of the warps of sampling.h, for reversible-jump MLT (Bitterli et al. 2017, sec. 6: "the
// inversion method ... we simply require an additional implementation of the CDF"). Each maps a point of
// the warp's output domain back to the unit square, so that warp(invert(x)) == x up to rounding, and the
// Jacobian |det du/dx| of that inverse equals the warp's density at x (the pdf in the measure the warp's
// pdf function uses). The caller checks that x lies in the warp's domain; these clamp to [0,1).
//
// Also here: the one-dimensional building blocks of probabilistic inverses (sec. 5-6):
//  - an ambiguous interval [a, b) of a coordinate (a discrete choice read from it, or an unused
//    coordinate with [a, b) = [0, 1)) is inverted to a + gamma (b - a) with Jacobian b - a (eq. 40);
//  - a choice among n techniques that could have produced x is made with the distribution T(t) of eq. 44,
//    and the number that made the choice is remapped to [0,1) inside the chosen interval, so that it can
//    be used once more (for the ambiguous interval of the chosen technique) and stays uniform.
#pragma once
#include <cmath>
#include <optional>

#include "common/core/vec.h"

namespace mlt {

// Clamp to the primary-sample range [0, kOneMinusEpsilon].
inline float clampPrimary(float u) { return std::clamp(u, 0.0f, kOneMinusEpsilon); }

// Eq. 40: the coordinate of an ambiguous interval [a, b) as a + gamma (b - a), guaranteed to lie in
// [a, b) after rounding to float (so a forward test `u < b` / `u >= a` reproduces the choice).
// Jacobian: b - a (returned by the callers as the probability of the discrete choice).
inline float invertInterval(double a, double b, float gamma) {
  float u = static_cast<float>(a + double(gamma) * (b - a));
  if (double(u) >= b) u = std::nextafter(static_cast<float>(b), 0.0f);
  while (double(u) >= b && u > 0) u = std::nextafter(u, 0.0f);
  while (double(u) < a) u = std::nextafter(u, 1.0f);
  return clampPrimary(u);
}

// Picks index t with probability weight[t] / sum (eq. 44) using gamma, and remaps gamma to [0,1) inside
// the chosen interval (*gammaRest), which is again uniform and independent of the choice. Returns -1 if
// every weight is zero.
inline int pickByWeight(const float* weight, int n, float gamma, float* gammaRest) {
  double total = 0;
  int last = -1;
  for (int i = 0; i < n; ++i)
    if (weight[i] > 0) {
      total += weight[i];
      last = i;
    }
  if (last < 0 || !(total > 0)) return -1;
  double acc = 0;
  for (int i = 0; i <= last; ++i) {
    if (!(weight[i] > 0)) continue;
    const double lo = acc / total;
    acc += weight[i];
    const double hi = i == last ? 1.0 : acc / total;
    if (double(gamma) < hi || i == last) {
      *gammaRest = clampPrimary(static_cast<float>((double(gamma) - lo) / (hi - lo)));
      return i;
    }
  }
  return -1;  // unreachable
}

// Inverse of sampleConcentricDisk (Shirley & Chiu 1997): a point of the unit disk -> u in [0,1)^2.
// Jacobian (per unit area of the disk): 1 / pi.
inline Vec2 invertConcentricDisk(Vec2 p) {
  const double x = p.x, y = p.y;
  const double r = std::sqrt(x * x + y * y);
  if (r == 0) return {0.5f, 0.5f};
  const double pi = 3.14159265358979323846;
  double phi = std::atan2(y, x);        // (-pi, pi]
  if (phi < -pi / 4) phi += 2 * pi;     // [-pi/4, 7pi/4)
  double ox, oy;
  if (phi < pi / 4) {                   // right wedge: r = ox > 0, theta = pi/4 oy/ox
    ox = r;
    oy = ox * phi / (pi / 4);
  } else if (phi < 3 * pi / 4) {        // top wedge: r = oy > 0, theta = pi/2 - pi/4 ox/oy
    oy = r;
    ox = oy * (pi / 2 - phi) / (pi / 4);
  } else if (phi < 5 * pi / 4) {        // left wedge: r = ox < 0, the point is at angle theta + pi
    ox = -r;
    oy = ox * (phi - pi) / (pi / 4);
  } else {                              // bottom wedge: r = oy < 0
    oy = -r;
    ox = oy * (pi / 2 - (phi - pi)) / (pi / 4);
  }
  return {clampPrimary(float(0.5 * (ox + 1))), clampPrimary(float(0.5 * (oy + 1)))};
}

// Inverse of sampleCosineHemisphere (Malley): the disk point is the direction's (x, y).
// Jacobian = cosineHemispherePdfW(w.z) = cos(theta) / pi.
inline Vec2 invertCosineHemisphere(const Vec3& w) { return invertConcentricDisk({w.x, w.y}); }

// Inverse of sampleUniformSphere: z = 1 - 2 u.x, phi = 2 pi u.y. Jacobian 1 / (4 pi).
inline Vec2 invertUniformSphere(const Vec3& w) {
  const double z = std::clamp(double(w.z), -1.0, 1.0);
  double phi = std::atan2(double(w.y), double(w.x));
  if (phi < 0) phi += 2 * 3.14159265358979323846;
  return {clampPrimary(float((1 - z) / 2)), clampPrimary(float(phi / (2 * 3.14159265358979323846)))};
}

// Inverse of sampleUniformCone: cos(theta) = (1 - u.x) + u.x cosThetaMax. Jacobian 1 / (2 pi (1 - cosThetaMax)).
inline Vec2 invertUniformCone(const Vec3& w, float cosThetaMax) {
  const double c = std::clamp(double(w.z), -1.0, 1.0);
  double phi = std::atan2(double(w.y), double(w.x));
  if (phi < 0) phi += 2 * 3.14159265358979323846;
  return {clampPrimary(float((1 - c) / (1 - double(cosThetaMax)))),
          clampPrimary(float(phi / (2 * 3.14159265358979323846)))};
}

// Inverse of sampleUniformConeNarrow(u, a) for a unit w: 1 - cos(theta) = (x^2 + y^2) / (1 + z) without
// cancellation. nullopt outside the cone. Jacobian 1 / (2 pi a).
inline std::optional<Vec2> invertUniformConeNarrow(const Vec3& w, float a) {
  if (!(w.z > 0)) return std::nullopt;
  const double oneMinusCos = (double(w.x) * w.x + double(w.y) * w.y) / (1 + double(w.z));
  const double ux = oneMinusCos / double(a);
  if (!(ux <= 1 + 1e-4)) return std::nullopt;
  double phi = std::atan2(double(w.y), double(w.x));
  if (phi < 0) phi += 2 * 3.14159265358979323846;
  return Vec2(clampPrimary(float(ux)), clampPrimary(float(phi / (2 * 3.14159265358979323846))));
}

// Inverse of sampleUniformTriangle: (b0, b1) = (1 - sqrt(u.x), u.y sqrt(u.x)). Jacobian 1 / area.
inline Vec2 invertUniformTriangle(double b0, double b1) {
  const double s = std::clamp(1 - b0, 0.0, 1.0);
  const double uy = s > 0 ? b1 / s : 0.5;
  return {clampPrimary(float(s * s)), clampPrimary(float(uy))};
}

// Russian roulette keeps a subpath when u < q: the survival decision is the ambiguous interval [0, q)
// (Jacobian q, the survival probability), termination [q, 1) (Jacobian 1 - q). nullopt if impossible.
struct RouletteInverse {
  float u = 0;
  float jacobian = 0;
};
inline std::optional<RouletteInverse> invertRoulette(float q, bool survived, float gamma) {
  q = std::clamp(q, 0.0f, 1.0f);
  if (survived ? !(q > 0) : !(q < 1)) return std::nullopt;
  if (survived) return RouletteInverse{invertInterval(0.0, q, gamma), q};
  return RouletteInverse{invertInterval(q, 1.0, gamma), 1 - q};
}

}  // namespace mlt
