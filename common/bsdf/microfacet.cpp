#include "common/bsdf/microfacet.h"

#include <algorithm>
#include <cmath>

namespace mlt {

namespace {
constexpr double kSqrtPi = 1.77245385090551602730;
constexpr double kPiD = 3.14159265358979323846;

// Inverse error function: Giles' single-precision approximation refined by Newton steps on erf.
double erfInv(double y) {
  y = std::clamp(y, -1 + 1e-15, 1 - 1e-15);
  double w = -std::log((1.0 - y) * (1.0 + y)), p;
  if (w < 5.0) {
    w = w - 2.5;
    p = 2.81022636e-08;
    p = 3.43273939e-07 + p * w;
    p = -3.5233877e-06 + p * w;
    p = -4.39150654e-06 + p * w;
    p = 0.00021858087 + p * w;
    p = -0.00125372503 + p * w;
    p = -0.00417768164 + p * w;
    p = 0.246640727 + p * w;
    p = 1.50140941 + p * w;
  } else {
    w = std::sqrt(w) - 3;
    p = -0.000200214257;
    p = 0.000100950558 + p * w;
    p = 0.00134934322 + p * w;
    p = -0.00367342844 + p * w;
    p = 0.00573950773 + p * w;
    p = -0.0076224613 + p * w;
    p = 0.00943887047 + p * w;
    p = 1.00167406 + p * w;
    p = 2.83297682 + p * w;
  }
  // One Newton step on erf(x) = y takes Giles' ~1e-7 relative error to ~1e-13.
  double x = p * y;
  const double d = 2 / kSqrtPi * std::exp(-x * x);
  if (d > 0) x -= (std::erf(x) - y) / d;
  return x;
}
}  // namespace

float Microfacet::D(const Vec3& m) const {
  if (m.z <= 0) return 0;
  const double c2 = double(m.z) * m.z, tan2 = std::max(0.0, 1 - c2) / c2, a2 = double(alpha_) * alpha_;
  if (type_ == MicrofacetType::GGX) {
    const double t = 1 + tan2 / a2;
    return float(1 / (kPiD * a2 * c2 * c2 * t * t));
  }
  return float(std::exp(-tan2 / a2) / (kPiD * a2 * c2 * c2));
}

float Microfacet::lambda(const Vec3& w) const {
  const double c2 = double(w.z) * w.z;
  if (c2 >= 1) return 0;
  const double tan2 = (1 - c2) / c2;
  if (type_ == MicrofacetType::GGX) return float(0.5 * (std::sqrt(1 + double(alpha_) * alpha_ * tan2) - 1));
  // Beckmann: a = 1 / (alpha tan(theta)); Lambda = (exp(-a^2) / (a sqrt(pi)) - erfc(a)) / 2.
  const double a = 1 / (alpha_ * std::sqrt(tan2));
  return float(0.5 * (std::exp(-a * a) / (a * kSqrtPi) - std::erfc(a)));
}

Vec3 Microfacet::sampleVisible(const Vec3& v, Vec2 u) const {
  return type_ == MicrofacetType::GGX ? sampleGGX(v, u) : sampleBeckmann(v, u);
}

// Heitz 2018, listing 1.
Vec3 Microfacet::sampleGGX(const Vec3& v, Vec2 u) const {
  const Vec3 vh = normalize(Vec3(alpha_ * v.x, alpha_ * v.y, v.z));
  const float lensq = vh.x * vh.x + vh.y * vh.y;
  const Vec3 t1 = lensq > 0 ? Vec3(-vh.y, vh.x, 0) / std::sqrt(lensq) : Vec3(1, 0, 0);
  const Vec3 t2 = cross(vh, t1);
  const float r = std::sqrt(u.x), phi = 2 * kPi * u.y;
  const float p1 = r * std::cos(phi);
  float p2 = r * std::sin(phi);
  const float s = 0.5f * (1 + vh.z);
  p2 = (1 - s) * std::sqrt(fmaxNum(0.0f, 1 - p1 * p1)) + s * p2;
  const Vec3 nh = p1 * t1 + p2 * t2 + std::sqrt(fmaxNum(0.0f, 1 - p1 * p1 - p2 * p2)) * vh;
  return normalize(Vec3(alpha_ * nh.x, alpha_ * nh.y, fmaxNum(1e-7f, nh.z)));
}

// Visible-normal sampling for Beckmann (Heitz & d'Eon 2014, sec. 4 and appendix; inversion as in
// pbrt-v3's BeckmannSample11): sample slopes of the unit-roughness distribution seen from the
// stretched direction, rotate, unstretch.
Vec3 Microfacet::sampleBeckmann(const Vec3& v, Vec2 u) const {
  const Vec3 vs = normalize(Vec3(alpha_ * v.x, alpha_ * v.y, v.z));
  const double cosThetaI = vs.z;
  const double u1 = std::clamp(double(u.x), 1e-9, 1 - 1e-9), u2 = std::clamp(double(u.y), 1e-9, 1 - 1e-9);
  double slopeX, slopeY;
  if (cosThetaI > 0.99999) {
    const double r = std::sqrt(-std::log(1 - u1)), phi = 2 * kPiD * u2;
    slopeX = r * std::cos(phi);
    slopeY = r * std::sin(phi);
  } else {
    // CDF of slope_x for the visible unit-roughness distribution seen at theta_i (Heitz & d'Eon 2014):
    // C(x) = (1 + erf(x) + tan/sqrt(pi) exp(-x^2)) / (1 + erf(cot) + tan/sqrt(pi) exp(-cot^2)), x <= cot,
    // C'(x) = 2/sqrt(pi) exp(-x^2) (1 - x tan) / (same). Safeguarded Newton in x from pbrt-v3's fitted guess.
    const double sinThetaI = std::sqrt(std::max(0.0, 1 - cosThetaI * cosThetaI));
    const double tanThetaI = sinThetaI / cosThetaI, cotThetaI = 1 / tanThetaI;
    const double erfCot = std::erf(cotThetaI);
    const double thetaI = std::acos(cosThetaI);
    const double fit = 1 + thetaI * (-0.876 + thetaI * (0.4265 - 0.0594 * thetaI));
    const double norm = 1 / (1 + erfCot + tanThetaI / kSqrtPi * std::exp(-cotThetaI * cotThetaI));
    double lo = -8, hi = cotThetaI;
    double x = std::clamp(erfInv(erfCot - (1 + erfCot) * std::pow(1 - u1, fit)), lo, hi);
    for (int it = 0; it < 100; ++it) {
      const double e = std::exp(-x * x);
      const double value = norm * (1 + std::erf(x) + tanThetaI / kSqrtPi * e) - u1;
      if (std::fabs(value) < 1e-9) break;
      if (value > 0) hi = x;
      else lo = x;
      if (hi - lo < 1e-12) break;
      const double derivative = norm * 2 / kSqrtPi * e * (1 - x * tanThetaI);
      double next = derivative > 0 ? x - value / derivative : 0.5 * (lo + hi);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      x = next;
    }
    slopeX = x;
    slopeY = erfInv(2 * u2 - 1);
  }
  // Rotate by the azimuth of the stretched direction, unstretch.
  const double sinT = std::sqrt(std::max(0.0, 1 - cosThetaI * cosThetaI));
  double cosPhi = 1, sinPhi = 0;
  if (sinT > 0) {
    cosPhi = std::clamp(vs.x / sinT, -1.0, 1.0);
    sinPhi = std::clamp(vs.y / sinT, -1.0, 1.0);
  }
  const double sx = cosPhi * slopeX - sinPhi * slopeY;
  const double sy = sinPhi * slopeX + cosPhi * slopeY;
  const double mx = -alpha_ * sx, my = -alpha_ * sy;
  const double len = std::sqrt(mx * mx + my * my + 1);
  return {float(mx / len), float(my / len), float(1 / len)};
}

// ---- Inverses (reversible-jump MLT; Bitterli et al. 2017, sec. 6 "inversion method") --------------------

std::optional<Vec2> Microfacet::invertVisible(const Vec3& v, const Vec3& m) const {
  if (!(v.z > 0) || !(m.z > 0) || !(dot(v, m) > 0)) return std::nullopt;
  return type_ == MicrofacetType::GGX ? invertGGX(v, m) : invertBeckmann(v, m);
}

// Heitz 2018, listing 1 backwards: stretch m to the hemisphere configuration nh, read its coordinates
// (p1, p2') in the frame (t1, t2, vh), undo the warp p2' = (1 - s) sqrt(1 - p1^2) + s p2 of the
// half-disk, and invert the uniform disk (r = sqrt(u1), phi = 2 pi u2).
std::optional<Vec2> Microfacet::invertGGX(const Vec3& v, const Vec3& m) const {
  const Vec3 vh = normalize(Vec3(alpha_ * v.x, alpha_ * v.y, v.z));
  const float lensq = vh.x * vh.x + vh.y * vh.y;
  const Vec3 t1 = lensq > 0 ? Vec3(-vh.y, vh.x, 0) / std::sqrt(lensq) : Vec3(1, 0, 0);
  const Vec3 t2 = cross(vh, t1);
  const Vec3 nh = normalize(Vec3(m.x / alpha_, m.y / alpha_, m.z));
  if (!(dot(nh, vh) >= -1e-4f)) return std::nullopt;
  const double p1 = dot(nh, t1), p2w = dot(nh, t2);
  const double s = 0.5 * (1 + double(vh.z));
  const double p2 = (p2w - (1 - s) * std::sqrt(std::max(0.0, 1 - p1 * p1))) / s;
  const double r2 = p1 * p1 + p2 * p2;
  if (!(r2 <= 1 + 1e-4)) return std::nullopt;
  double phi = std::atan2(p2, p1);
  if (phi < 0) phi += 2 * kPiD;
  return Vec2(std::clamp(float(r2), 0.0f, kOneMinusEpsilon), std::clamp(float(phi / (2 * kPiD)), 0.0f, kOneMinusEpsilon));
}

// sampleBeckmann backwards: the slopes of m, rotated back by the azimuth of the stretched direction, are
// (slopeX, slopeY); u1 is the visible slope CDF C(slopeX) (the function sampleBeckmann inverts by Newton),
// u2 = (1 + erf(slopeY)) / 2. Near normal incidence the slopes are polar: r^2 = -log(1 - u1), phi = 2 pi u2.
std::optional<Vec2> Microfacet::invertBeckmann(const Vec3& v, const Vec3& m) const {
  const Vec3 vs = normalize(Vec3(alpha_ * v.x, alpha_ * v.y, v.z));
  const double cosThetaI = vs.z;
  const double sx = -double(m.x) / (double(alpha_) * m.z), sy = -double(m.y) / (double(alpha_) * m.z);
  const double sinT = std::sqrt(std::max(0.0, 1 - cosThetaI * cosThetaI));
  double cosPhi = 1, sinPhi = 0;
  if (sinT > 0) {
    cosPhi = std::clamp(vs.x / sinT, -1.0, 1.0);
    sinPhi = std::clamp(vs.y / sinT, -1.0, 1.0);
  }
  // The forward rotation [cosPhi -sinPhi; sinPhi cosPhi] is not exactly orthonormal near normal incidence
  // (sinT from a float cosine): invert the 2x2 matrix itself, not its transpose.
  const double det = cosPhi * cosPhi + sinPhi * sinPhi;
  const double slopeX = (cosPhi * sx + sinPhi * sy) / det, slopeY = (-sinPhi * sx + cosPhi * sy) / det;
  double u1, u2;
  if (cosThetaI > 0.99999) {
    u1 = 1 - std::exp(-(slopeX * slopeX + slopeY * slopeY));
    double phi = std::atan2(slopeY, slopeX);
    if (phi < 0) phi += 2 * kPiD;
    u2 = phi / (2 * kPiD);
  } else {
    const double tanThetaI = sinT / cosThetaI, cotThetaI = 1 / tanThetaI;
    if (!(slopeX <= cotThetaI * (1 + 1e-6) + 1e-9)) return std::nullopt;  // a back-facing microfacet
    const double erfCot = std::erf(cotThetaI);
    const double norm = 1 / (1 + erfCot + tanThetaI / kSqrtPi * std::exp(-cotThetaI * cotThetaI));
    u1 = norm * (1 + std::erf(slopeX) + tanThetaI / kSqrtPi * std::exp(-slopeX * slopeX));
    u2 = 0.5 * (1 + std::erf(slopeY));
  }
  return Vec2(std::clamp(float(u1), 0.0f, kOneMinusEpsilon), std::clamp(float(u2), 0.0f, kOneMinusEpsilon));
}

}  // namespace mlt
