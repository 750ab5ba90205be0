// Isotropic microfacet distributions (GGX / Trowbridge-Reitz and Beckmann) with the Smith
// shadowing-masking function and sampling of the distribution of visible normals (VNDF):
//  - GGX: Heitz 2018, "Sampling the GGX distribution of visible normals" (exact).
//  - Beckmann: Heitz & d'Eon 2014 / Jakob's numerical inversion of the slope CDF (as in pbrt-v3),
//    solved here in double precision to ~1e-9 so sampling matches pdfVisible.
// Local frame, microfacet normals m in the upper hemisphere.
#pragma once
#include <optional>

#include "common/core/vec.h"
#include "common/scene/scene_desc.h"

namespace mlt {

class Microfacet {
 public:
  Microfacet(MicrofacetType type, float alpha) : type_(type), alpha_(alpha) {}
  MicrofacetType type() const { return type_; }
  float alpha() const { return alpha_; }

  // Normal distribution D(m) (per unit projected area: int D(m) cos(theta_m) dm = 1).
  float D(const Vec3& m) const;
  // Smith's Lambda(w) (Heitz 2014, eq. 72 (GGX) and eq. 73 (Beckmann, exact with erfc)).
  float lambda(const Vec3& w) const;
  // Smith's monodirectional masking G1(w, m), 0 if w sees the back of m relative to the macro normal.
  float G1(const Vec3& w, const Vec3& m) const {
    if (dot(w, m) * w.z <= 0) return 0;
    return 1 / (1 + lambda(w));
  }
  // Separable shadowing-masking G(wo, wi, m) = G1(wo, m) G1(wi, m) (as Mitsuba).
  float G(const Vec3& wo, const Vec3& wi, const Vec3& m) const { return G1(wo, m) * G1(wi, m); }

  // Samples m from the distribution of normals visible from v (v.z > 0):
  // D_v(m) = G1(v) max(0, v.m) D(m) / v.z  (Heitz 2014, eq. 2).
  Vec3 sampleVisible(const Vec3& v, Vec2 u) const;
  // Inverse of sampleVisible (reversible-jump MLT): the u with which sampleVisible(v, u) returns m, or
  // nullopt if m is not visible from v. Jacobian |du/dm| = pdfVisible(v, m).
  std::optional<Vec2> invertVisible(const Vec3& v, const Vec3& m) const;
  float pdfVisible(const Vec3& v, const Vec3& m) const {
    if (v.z <= 0) return 0;
    const float vm = dot(v, m);
    if (vm <= 0) return 0;
    return D(m) * vm / ((1 + lambda(v)) * v.z);
  }

 private:
  Vec3 sampleGGX(const Vec3& v, Vec2 u) const;
  Vec3 sampleBeckmann(const Vec3& v, Vec2 u) const;
  std::optional<Vec2> invertGGX(const Vec3& v, const Vec3& m) const;
  std::optional<Vec2> invertBeckmann(const Vec3& v, const Vec3& m) const;
  MicrofacetType type_;
  float alpha_;
};

}  // namespace mlt
