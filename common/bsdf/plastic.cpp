// Mitsuba's smooth `plastic`: a smooth dielectric coat (delta specular reflection, Fresnel F) over an
// ideal diffuse base. Light that enters the coat is reflected diffusely and bounces inside the coat; the
// internal reflections are folded into the base albedo (Mitsuba 0.6 plastic.cpp):
//   f_diffuse(wo, wi) = rho' (1 - F(cos_o)) (1 - F(cos_i)) / (pi eta^2)
//   rho' = rho / (1 - Fdr_int)           (linear, default: preserves texture colours)
//   rho' = rho / (1 - rho Fdr_int)       (nonlinear: the geometric series of internal bounces)
// with Fdr_int the hemispherical-average reflectance of the coat seen from inside. The component is
// chosen with probability P_spec = F w / (F w + (1 - F)(1 - w)), w = the specular sampling weight
// (luminance of the specular reflectance over specular + mean diffuse luminance).
#include <cmath>

#include "common/bsdf/bsdfs.h"
#include "common/bsdf/fresnel.h"
#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"

namespace mlt {

namespace {

class Plastic final : public Bsdf {
 public:
  Plastic(float eta, TexturePtr diffuse, TexturePtr specR, bool nonlinear)
      : eta_(eta), diffuse_(std::move(diffuse)), specR_(std::move(specR)), nonlinear_(nonlinear) {
    fdrInt_ = fresnelDiffuseReflectance(1 / eta_);
    invEta2_ = 1 / (eta_ * eta_);
    const float d = luminance(diffuse_->average()), s = luminance(specR_->average());
    specularWeight_ = d + s > 0 ? s / (d + s) : 0.5f;
  }

  Color eval(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const override {
    if (wo.z <= 0 || wi.z <= 0) return Color(0.0f);
    const float Fo = fresnelDielectric(wo.z, eta_), Fi = fresnelDielectric(wi.z, eta_);
    return base(q.uv) * (kInvPi * invEta2_ * (1 - Fo) * (1 - Fi));
  }
  float pdf(const Vec3& wo, const Vec3& wi, const BsdfQuery&) const override {
    if (wo.z <= 0 || wi.z <= 0) return 0;
    return (1 - probSpecular(wo.z)) * cosineHemispherePdfW(wi.z);
  }
  std::optional<BsdfSample> sample(const Vec3& wo, float uc, Vec2 uDir, const BsdfQuery& q) const override {
    if (wo.z <= 0) return std::nullopt;
    const float pSpec = probSpecular(wo.z);
    BsdfSample s;
    if (uc < pSpec) {
      const float F = fresnelDielectric(wo.z, eta_);
      s.wi = reflectZ(wo);
      s.f = specR_->eval(q.uv) * (F / wo.z);
      s.pdfW = s.pdfRevW = pSpec;
      s.delta = true;
      return s;
    }
    s.wi = sampleCosineHemisphere(uDir);
    if (s.wi.z <= 0) return std::nullopt;
    s.f = eval(wo, s.wi, q);
    s.pdfW = pdf(wo, s.wi, q);
    s.pdfRevW = pdf(s.wi, wo, q);
    return s;
  }
  // Inverse: the Dirac coat reflection owns the mirror direction (the diffuse lobe reaches it with
  // probability zero): uComponent in [0, P_spec), uDir unread (gamma.fill), Jacobian P_spec. Any other
  // direction is diffuse: uComponent in [P_spec, 1), uDir inverts the cosine hemisphere, Jacobian = pdf.
  std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                const BsdfQuery& q) const override {
    if (wo.z <= 0) return std::nullopt;
    const float pSpec = probSpecular(wo.z);
    if (sameDeltaDirection(wi, reflectZ(wo))) {
      if (!(pSpec > 0)) return std::nullopt;
      return BsdfSampleInverse{invertInterval(0, pSpec, gamma.pick), gamma.fill, pSpec};
    }
    if (wi.z <= 0 || !(pSpec < 1)) return std::nullopt;
    return BsdfSampleInverse{invertInterval(pSpec, 1, gamma.pick), invertCosineHemisphere(wi), pdf(wo, wi, q)};
  }
  bool isDelta() const override { return false; }
  // Normal-incidence estimate: specular F(1) plus the diffuse albedo (1 - F) rho.
  Color albedo(const Vec2& uv) const override {
    const float F = fresnelDielectric(1, eta_);
    return specR_->eval(uv) * F + diffuse_->eval(uv) * (1 - F);
  }

  float probSpecular(float cosO) const {
    const float F = fresnelDielectric(cosO, eta_);
    const float a = F * specularWeight_, b = (1 - F) * (1 - specularWeight_);
    return a + b > 0 ? a / (a + b) : 0;
  }

 private:
  Color base(Vec2 uv) const {
    const Color rho = diffuse_->eval(uv);
    if (nonlinear_) return rho / (Color(1.0f) - rho * fdrInt_);
    return rho / (1 - fdrInt_);
  }
  float eta_;
  TexturePtr diffuse_;
  TexturePtr specR_;
  bool nonlinear_;
  float fdrInt_, invEta2_, specularWeight_;
};

}  // namespace

std::unique_ptr<Bsdf> makePlastic(float eta, TexturePtr diffuse, TexturePtr specR, bool nonlinear) {
  return std::make_unique<Plastic>(eta, std::move(diffuse), std::move(specR), nonlinear);
}

}  // namespace mlt
