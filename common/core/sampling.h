// Warps from the unit square to common domains, each with its density in the measure named by the
// function (pdfW: solid angle, pdfA: area). Every sampling routine in the renderer is built from these
// and reads its numbers from a SampleSource, so a Markov chain can mutate them.
#pragma once
#include <cmath>

#include "common/core/vec.h"

namespace mlt {

inline Vec2 sampleConcentricDisk(Vec2 u) {
  const Vec2 o{2 * u.x - 1, 2 * u.y - 1};
  if (o.x == 0 && o.y == 0) return {0, 0};
  float r, theta;
  if (std::fabs(o.x) > std::fabs(o.y)) {
    r = o.x;
    theta = (kPi / 4) * (o.y / o.x);
  } else {
    r = o.y;
    theta = (kPi / 2) - (kPi / 4) * (o.x / o.y);
  }
  return {r * std::cos(theta), r * std::sin(theta)};
}

// Cosine-weighted hemisphere around +z (Malley's method). pdfW = cos(theta) / pi.
inline Vec3 sampleCosineHemisphere(Vec2 u) {
  const Vec2 d = sampleConcentricDisk(u);
  const float z = std::sqrt(fmaxNum(0.0f, 1 - d.x * d.x - d.y * d.y));
  return {d.x, d.y, z};
}
inline float cosineHemispherePdfW(float cosTheta) { return cosTheta > 0 ? cosTheta * kInvPi : 0.0f; }

inline Vec3 sampleUniformSphere(Vec2 u) {
  const float z = 1 - 2 * u.x;
  const float r = std::sqrt(fmaxNum(0.0f, 1 - z * z));
  const float phi = 2 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}
inline constexpr float uniformSpherePdfW() { return kInv4Pi; }

inline Vec3 sampleUniformHemisphere(Vec2 u) {
  const float z = u.x;
  const float r = std::sqrt(fmaxNum(0.0f, 1 - z * z));
  const float phi = 2 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}
inline constexpr float uniformHemispherePdfW() { return kInv2Pi; }

// Uniform in the cone of directions within acos(cosThetaMax) of +z. pdfW = 1 / (2 pi (1 - cosThetaMax)).
inline Vec3 sampleUniformCone(Vec2 u, float cosThetaMax) {
  const float cosTheta = (1 - u.x) + u.x * cosThetaMax;
  const float sinTheta = std::sqrt(fmaxNum(0.0f, 1 - cosTheta * cosTheta));
  const float phi = u.y * 2 * kPi;
  return {std::cos(phi) * sinTheta, std::sin(phi) * sinTheta, cosTheta};
}
inline float uniformConePdfW(float cosThetaMax) { return 1 / (2 * kPi * (1 - cosThetaMax)); }
// The same cone given by a = 1 - cosThetaMax, accurate for narrow cones: with cos(theta) itself a light
// 0.003 rad wide has a ~ 5e-6 and float cosines near 1 step by 6e-8, so the cone would hold only ~75
// distinct rings. Here 1 - cos(theta) = u.x a and sin^2(theta) = (1 - cos)(1 + cos) = u.x a (2 - u.x a),
// both without cancellation. pdfW = 1 / (2 pi a).
inline Vec3 sampleUniformConeNarrow(Vec2 u, float a) {
  const float oneMinusCos = u.x * a;
  const float sinTheta = std::sqrt(fmaxNum(0.0f, oneMinusCos * (2 - oneMinusCos)));
  const float phi = u.y * 2 * kPi;
  return {std::cos(phi) * sinTheta, std::sin(phi) * sinTheta, 1 - oneMinusCos};
}

// Uniform barycentrics on a triangle; pdfA = 1 / area. Returns (b0, b1); b2 = 1 - b0 - b1.
inline Vec2 sampleUniformTriangle(Vec2 u) {
  const float su0 = std::sqrt(u.x);
  return {1 - su0, u.y * su0};
}

// Conversions between measures (Veach 1997, eq. 8.10): pdfA = pdfW * |cos(theta_y)| / |x - y|^2.
inline float pdfWToA(float pdfW, float distSquared, float absCosAtTarget) {
  return pdfW * absCosAtTarget / distSquared;
}
inline float pdfAToW(float pdfA, float distSquared, float absCosAtTarget) {
  return absCosAtTarget > 0 ? pdfA * distSquared / absCosAtTarget : 0.0f;
}

// MIS heuristics (Veach 1997, sec. 9.2) for two strategies with nf, ng samples.
inline float powerHeuristic(float fPdf, float gPdf) {
  const float f = fPdf * fPdf, g = gPdf * gPdf;
  return f + g > 0 ? f / (f + g) : 0.0f;
}
inline float balanceHeuristic(float fPdf, float gPdf) { return fPdf + gPdf > 0 ? fPdf / (fPdf + gPdf) : 0.0f; }

// Spherical coordinates helpers for environment lookups and tests.
inline float sphericalTheta(const Vec3& v) { return std::acos(std::clamp(v.z, -1.0f, 1.0f)); }
inline float sphericalPhi(const Vec3& v) {
  const float p = std::atan2(v.y, v.x);
  return p < 0 ? p + 2 * kPi : p;
}

}  // namespace mlt
