// Rough metal (Mitsuba's `roughconductor`). One-sided, as in Mitsuba: zero when wo is on the back.
// Torrance-Sparrow with the Smith G and exact conductor Fresnel at the half vector,
// f = F(wo.h) D(h) G(wo, wi, h) / (4 cos_o cos_i) (Walter et al. 2007, eq. 20), sampled through the
// visible normals seen from wo.
#include <cmath>

#include "common/bsdf/bsdfs.h"
#include "common/bsdf/fresnel.h"
#include "common/bsdf/microfacet.h"
#include "common/core/sampling_inverse.h"

namespace mlt {

namespace {

class RoughConductor final : public Bsdf {
 public:
  RoughConductor(MicrofacetType t, float alpha, Color eta, Color k, bool mirror, Color r)
      : mf_(t, alpha), eta_(eta), k_(k), mirror_(mirror), specR_(r) {}

  Color eval(const Vec3& wo, const Vec3& wi, const BsdfQuery&) const override {
    if (wo.z <= 0 || wi.z <= 0) return Color(0.0f);
    const Vec3 h = normalize(wo + wi);
    const float D = mf_.D(h);
    if (D == 0) return Color(0.0f);
    const float G = mf_.G(wo, wi, h);
    return specR_ * fresnel(dot(wo, h)) * (D * G / (4 * wo.z * wi.z));
  }
  // pdfW(wi) = D_wo(h) / (4 |wo.h|) (Walter et al. 2007, eq. 14 with the reflection Jacobian).
  float pdf(const Vec3& wo, const Vec3& wi, const BsdfQuery&) const override {
    if (wo.z <= 0 || wi.z <= 0) return 0;
    const Vec3 h = normalize(wo + wi);
    const float woh = dot(wo, h);
    if (woh <= 0) return 0;
    return mf_.pdfVisible(wo, h) / (4 * woh);
  }
  std::optional<BsdfSample> sample(const Vec3& wo, float, Vec2 uDir, const BsdfQuery& q) const override {
    if (wo.z <= 0) return std::nullopt;
    const Vec3 m = mf_.sampleVisible(wo, uDir);
    BsdfSample s;
    s.wi = reflectAbout(wo, m);
    if (s.wi.z <= 0) return std::nullopt;  // reflected below the horizon: absorbed (its mass is excluded from pdf)
    s.f = eval(wo, s.wi, q);
    s.pdfW = pdf(wo, s.wi, q);
    s.pdfRevW = pdf(s.wi, wo, q);
    if (s.pdfW <= 0) return std::nullopt;
    return s;
  }
  // Inverse: the half vector is the sampled microfacet normal; uDir inverts the visible-normal routine,
  // uComponent is unread (gamma.pick). Jacobian = pdf (= D_wo(h) / (4 wo.h)).
  std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                const BsdfQuery& q) const override {
    if (wo.z <= 0 || wi.z <= 0) return std::nullopt;
    const float pdfW = pdf(wo, wi, q);
    if (!(pdfW > 0)) return std::nullopt;
    const std::optional<Vec2> uDir = mf_.invertVisible(wo, normalize(wo + wi));
    if (!uDir) return std::nullopt;
    return BsdfSampleInverse{clampPrimary(gamma.pick), *uDir, pdfW};
  }
  bool isDelta() const override { return false; }
  Color albedo(const Vec2&) const override { return specR_ * fresnel(1); }

 private:
  Color fresnel(float c) const { return mirror_ ? Color(1.0f) : fresnelConductor(std::fmin(1.0f, c), eta_, k_); }
  Microfacet mf_;
  Color eta_, k_;
  bool mirror_;
  Color specR_;
};

}  // namespace

std::unique_ptr<Bsdf> makeRoughConductor(MicrofacetType t, float alpha, Color eta, Color k, bool mirror, Color r) {
  return std::make_unique<RoughConductor>(t, alpha, eta, k, mirror, r);
}

}  // namespace mlt
