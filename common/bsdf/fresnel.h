// Fresnel equations and the local-frame reflection/refraction helpers shared by the BSDFs.
// Convention (Mitsuba's): eta = n_int / n_ext; a direction with z > 0 is on the exterior side.
#pragma once
#include <cmath>

#include "common/core/color.h"
#include "common/core/vec.h"

namespace mlt {

// Unpolarized Fresnel reflectance of a smooth dielectric interface (Born & Wolf; Walter et al. 2007,
// eq. 22). cosThetaI is signed: > 0 means incidence from the exterior. On return *cosThetaT holds the
// signed cosine of the refracted direction (opposite sign to cosThetaI), 0 under total internal reflection.
inline float fresnelDielectric(float cosThetaI, float eta, float* cosThetaT = nullptr) {
  if (eta == 1) {
    if (cosThetaT) *cosThetaT = -cosThetaI;
    return 0;
  }
  // etaRel = n_t / n_i for the side the light arrives from.
  const float etaRel = cosThetaI > 0 ? eta : 1 / eta;
  const float sin2I = fmaxNum(0.0f, 1 - cosThetaI * cosThetaI);
  const float cos2T = 1 - sin2I / (etaRel * etaRel);
  if (cos2T <= 0) {
    if (cosThetaT) *cosThetaT = 0;
    return 1;
  }
  const float cI = std::fabs(cosThetaI), cT = std::sqrt(cos2T);
  const float rs = (cI - etaRel * cT) / (cI + etaRel * cT);
  const float rp = (etaRel * cI - cT) / (etaRel * cI + cT);
  if (cosThetaT) *cosThetaT = cosThetaI > 0 ? -cT : cT;
  return 0.5f * (rs * rs + rp * rp);
}

// Fresnel reflectance of a conductor with complex IOR eta + i k (relative to the exterior), exact
// unpolarized form for one channel (e.g. Mitsuba's fresnelConductorExact). cosThetaI in [0, 1].
inline float fresnelConductor1(float cosThetaI, float eta, float k) {
  const float c2 = cosThetaI * cosThetaI, s2 = 1 - c2, s4 = s2 * s2;
  const float t1 = eta * eta - k * k - s2;
  const float a2pb2 = std::sqrt(fmaxNum(0.0f, t1 * t1 + 4 * k * k * eta * eta));
  const float a = std::sqrt(fmaxNum(0.0f, 0.5f * (a2pb2 + t1)));
  const float term1 = a2pb2 + c2, term2 = 2 * a * cosThetaI;
  const float rs = (term1 - term2) / (term1 + term2);
  const float term3 = a2pb2 * c2 + s4, term4 = term2 * s2;
  const float rp = rs * (term3 - term4) / (term3 + term4);
  return 0.5f * (rp + rs);
}
inline Color fresnelConductor(float cosThetaI, const Color& eta, const Color& k) {
  return {fresnelConductor1(cosThetaI, eta.r, k.r), fresnelConductor1(cosThetaI, eta.g, k.g),
          fresnelConductor1(cosThetaI, eta.b, k.b)};
}

// Hemispherical average of the Fresnel reflectance for light arriving from the side where the relative
// IOR is eta: Fdr = 2 int_0^1 F(mu) mu dmu (numerically, Simpson with 2^14 intervals). Computed once per BSDF.
inline float fresnelDiffuseReflectance(float eta) {
  const int n = 1 << 14;
  double sum = 0;
  for (int i = 0; i <= n; ++i) {
    const double mu = double(i) / n;
    const double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    sum += w * fresnelDielectric(float(mu), eta) * mu;
  }
  return float(2 * sum / (3.0 * n));
}

// Mirror reflection about the normal (local frame).
inline Vec3 reflectZ(const Vec3& w) { return {-w.x, -w.y, w.z}; }
// Mirror reflection about a microfacet normal m.
inline Vec3 reflectAbout(const Vec3& w, const Vec3& m) { return 2 * dot(w, m) * m - w; }
// Refraction through the smooth interface (normal z) given the signed cosThetaT from fresnelDielectric.
inline Vec3 refractZ(const Vec3& w, float cosThetaT, float eta) {
  const float scale = -(cosThetaT < 0 ? 1 / eta : eta);
  return {scale * w.x, scale * w.y, cosThetaT};
}
// Refraction through a microfacet with normal m (any orientation) given fresnelDielectric(dot(w, m))'s
// cosThetaT (Walter et al. 2007, eq. 40).
inline Vec3 refractAbout(const Vec3& w, const Vec3& m, float cosThetaT, float eta) {
  const float cosI = dot(w, m);
  const float scale = cosThetaT < 0 ? 1 / eta : eta;
  return m * (cosI * scale + cosThetaT) - w * scale;
}

}  // namespace mlt
