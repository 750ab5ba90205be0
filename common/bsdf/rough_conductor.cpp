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
  RoughConductor(MicrofacetType t, float alpha, TexturePtr alphaTex, Color eta, Color k, bool mirror, TexturePtr r)
      : mf_(t, alpha), alphaTex_(std::move(alphaTex)), eta_(eta), k_(k), mirror_(mirror), specR_(std::move(r)) {
    reads_.component = false;
  }

  Color eval(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const override {
    if (wo.z <= 0 || wi.z <= 0) return Color(0.0f);
    const Vec3 h = normalize(wo + wi);
    const Microfacet mf = microfacet(q);
    const float D = mf.D(h);
    if (D == 0) return Color(0.0f);
    const float G = mf.G(wo, wi, h);
    return specR_->eval(q.uv) * fresnel(dot(wo, h)) * (D * G / (4 * wo.z * wi.z));
  }
  // pdfW(wi) = D_wo(h) / (4 |wo.h|) (Walter et al. 2007, eq. 14 with the reflection Jacobian).
  float pdf(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const override {
    if (wo.z <= 0 || wi.z <= 0) return 0;
    const Vec3 h = normalize(wo + wi);
    const float woh = dot(wo, h);
    if (woh <= 0) return 0;
    return microfacet(q).pdfVisible(wo, h) / (4 * woh);
  }
  std::optional<BsdfSample> sample(const Vec3& wo, float, Vec2 uDir, const BsdfQuery& q) const override {
    if (wo.z <= 0) return std::nullopt;
    const Vec3 m = microfacet(q).sampleVisible(wo, uDir);
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
  Color albedo(const Vec2& uv) const override { return specR_->eval(uv) * fresnel(1); }

 private:
  // The distribution at the hit: alpha from the texture (its luminance) when roughness is textured.
  Microfacet microfacet(const BsdfQuery& q) const {
    return alphaTex_ ? Microfacet(mf_.type(), textureAlpha(*alphaTex_, q.uv)) : mf_;
  }
  Color fresnel(float c) const { return mirror_ ? Color(1.0f) : fresnelConductor(std::fmin(1.0f, c), eta_, k_); }
  Microfacet mf_;
  TexturePtr alphaTex_;  // null: constant alpha (mf_)
  Color eta_, k_;
  bool mirror_;
  TexturePtr specR_;
};

}  // namespace

std::unique_ptr<Bsdf> makeRoughConductor(MicrofacetType t, float alpha, TexturePtr alphaTex, Color eta, Color k, bool mirror,
                                         TexturePtr r) {
  return std::make_unique<RoughConductor>(t, alpha, std::move(alphaTex), eta, k, mirror, std::move(r));
}

}  // namespace mlt
