// Rough dielectric interface (Mitsuba's `roughdielectric`; Walter et al. 2007, "Microfacet models for
// refraction through rough surfaces"). eta = n_int / n_ext, z > 0 is the exterior.
//
// For a pair (wo, wi) let eta_o be the IOR on wo's side and eta_i on wi's (etaRel = eta_i / eta_o).
//  reflection:   h = normalize(wo + wi)                          f = F D G / (4 |cos_o| |cos_i|)
//  transmission: h = -normalize(wo + etaRel wi)  (eq. 16)        f = (1-F) D G etaRel^2 |wo.h| |wi.h|
//                                                                    / (|cos_o| |cos_i| (wo.h + etaRel wi.h)^2)   (eq. 21)
// with h flipped to the exterior side, F = F(wo.h), G = G1(wo,h) G1(wi,h). In Radiance mode the
// transmitted value is multiplied by 1/etaRel^2 (radiance compression; Veach 1997, eq. 5.12), which makes
// f_rad(wo, wi) = f_imp(wi, wo): the adjoint BSDF (Veach 1997, sec. 5.3).
// Sampling: h from the visible normals seen from wo (mirrored to the exterior side), reflection with
// probability F(wo.h) else refraction; pdfW = D_wo(h) {F | 1-F} |dh/dwi| with
// dh/dwi = 1 / (4 |wi.h|) (eq. 14) or etaRel^2 |wi.h| / (wo.h + etaRel wi.h)^2 (eq. 17).
#include <cmath>

#include "common/bsdf/bsdfs.h"
#include "common/bsdf/fresnel.h"
#include "common/bsdf/microfacet.h"
#include "common/core/sampling_inverse.h"

namespace mlt {

namespace {

class RoughDielectric final : public Bsdf {
 public:
  RoughDielectric(MicrofacetType t, float alpha, TexturePtr alphaTex, float eta, TexturePtr r, TexturePtr tr)
      : mf_(t, alpha), alphaTex_(std::move(alphaTex)), eta_(eta), specR_(std::move(r)), specT_(std::move(tr)) {}

  // The half vector of a pair, oriented to the exterior; false if the pair cannot be connected
  // (grazing, back-facing microfacet, or degenerate).
  struct Half {
    Vec3 h;
    bool reflect;
    float etaRel;  // eta_i / eta_o (1 for reflection)
  };
  std::optional<Half> halfVector(const Vec3& wo, const Vec3& wi) const {
    if (wo.z == 0 || wi.z == 0) return std::nullopt;
    Half r;
    r.reflect = wo.z * wi.z > 0;
    r.etaRel = r.reflect ? 1.0f : (wo.z > 0 ? eta_ : 1 / eta_);
    Vec3 h = wo + wi * r.etaRel;
    const float len2 = lengthSquared(h);
    if (!(len2 > 0)) return std::nullopt;
    h = h / std::sqrt(len2);
    if (h.z < 0) h = -h;
    if (h.z == 0) return std::nullopt;
    // Discard back-facing microfacets: each direction must be on the same side of h as of the macro normal.
    if (dot(wo, h) * wo.z <= 0 || dot(wi, h) * wi.z <= 0) return std::nullopt;
    r.h = h;
    return r;
  }

  Color eval(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const override {
    const std::optional<Half> hv = halfVector(wo, wi);
    if (!hv) return Color(0.0f);
    const Vec3& h = hv->h;
    const Microfacet mf = microfacet(q);
    const float D = mf.D(h);
    if (D == 0) return Color(0.0f);
    const float woh = dot(wo, h), wih = dot(wi, h);
    const float F = fresnelDielectric(woh, eta_);
    const float G = mf.G(wo, wi, h);
    const float cosO = std::fabs(wo.z), cosI = std::fabs(wi.z);
    if (hv->reflect) return specR_->eval(q.uv) * (F * D * G / (4 * cosO * cosI));
    const float e = hv->etaRel, denom = woh + e * wih;
    float value = (1 - F) * D * G * e * e * std::fabs(woh * wih) / (cosO * cosI * denom * denom);
    if (q.mode == TransportMode::Radiance) value /= e * e;
    return specT_->eval(q.uv) * value;
  }

  float pdf(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const override {
    const std::optional<Half> hv = halfVector(wo, wi);
    if (!hv) return 0;
    const Vec3& h = hv->h;
    const float woh = dot(wo, h), wih = dot(wi, h);
    const Vec3 woUp = wo.z > 0 ? wo : -wo;
    const float pdfH = microfacet(q).pdfVisible(woUp, h);
    const float F = fresnelDielectric(woh, eta_);
    if (hv->reflect) return pdfH * F / (4 * std::fabs(wih));
    const float e = hv->etaRel, denom = woh + e * wih;
    return pdfH * (1 - F) * e * e * std::fabs(wih) / (denom * denom);
  }

  std::optional<BsdfSample> sample(const Vec3& wo, float uc, Vec2 uDir, const BsdfQuery& q) const override {
    if (wo.z == 0) return std::nullopt;
    const Vec3 woUp = wo.z > 0 ? wo : -wo;
    const Vec3 m = microfacet(q).sampleVisible(woUp, uDir);
    float cosThetaT;
    const float F = fresnelDielectric(dot(wo, m), eta_, &cosThetaT);
    BsdfSample s;
    if (uc < F) {
      s.wi = reflectAbout(wo, m);
      if (s.wi.z * wo.z <= 0) return std::nullopt;
      s.eta = 1;
    } else {
      s.wi = normalize(refractAbout(wo, m, cosThetaT, eta_));
      if (s.wi.z * wo.z >= 0) return std::nullopt;
      s.eta = wo.z > 0 ? eta_ : 1 / eta_;
    }
    s.pdfW = pdf(wo, s.wi, q);
    if (!(s.pdfW > 0)) return std::nullopt;
    s.f = eval(wo, s.wi, q);
    s.pdfRevW = pdf(s.wi, wo, q);
    return s;
  }

  // Inverse: the generalized half vector (eq. 16, oriented to the exterior) is the sampled microfacet
  // normal m; uDir inverts the visible normals seen from wo (mirrored up); the side of wi decides the
  // lobe, so uComponent lies in [0, F(wo.m)) for reflection or [F, 1) for refraction (eq. 40).
  // Jacobian = pdf (which includes F or 1 - F).
  std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                const BsdfQuery& q) const override {
    const std::optional<Half> hv = halfVector(wo, wi);
    if (!hv) return std::nullopt;
    const float pdfW = pdf(wo, wi, q);
    if (!(pdfW > 0)) return std::nullopt;
    const Vec3 woUp = wo.z > 0 ? wo : -wo;
    const std::optional<Vec2> uDir = mf_.invertVisible(woUp, hv->h);
    if (!uDir) return std::nullopt;
    const float F = fresnelDielectric(dot(wo, hv->h), eta_);
    if (hv->reflect ? !(F > 0) : !(F < 1)) return std::nullopt;
    const float uc = hv->reflect ? invertInterval(0, F, gamma.pick) : invertInterval(F, 1, gamma.pick);
    return BsdfSampleInverse{uc, *uDir, pdfW};
  }
  bool isDelta() const override { return false; }
  Color albedo(const Vec2& uv) const override {
    const Color r = specR_->eval(uv), t = specT_->eval(uv);
    return {std::fmax(r.r, t.r), std::fmax(r.g, t.g), std::fmax(r.b, t.b)};
  }

 private:
  // The distribution at the hit: alpha from the texture (its luminance) when roughness is textured.
  Microfacet microfacet(const BsdfQuery& q) const {
    return alphaTex_ ? Microfacet(mf_.type(), textureAlpha(*alphaTex_, q.uv)) : mf_;
  }
  Microfacet mf_;
  TexturePtr alphaTex_;  // null: constant alpha (mf_)
  float eta_;
  TexturePtr specR_, specT_;
};

}  // namespace

std::unique_ptr<Bsdf> makeRoughDielectric(MicrofacetType t, float alpha, TexturePtr alphaTex, float eta, TexturePtr r,
                                          TexturePtr tr) {
  return std::make_unique<RoughDielectric>(t, alpha, std::move(alphaTex), eta, std::move(r), std::move(tr));
}

}  // namespace mlt
