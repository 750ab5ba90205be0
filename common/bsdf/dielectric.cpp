// Smooth dielectric interface (Mitsuba's `dielectric`). A pure Dirac BSDF: eval/pdf are 0, sample()
// picks reflection or transmission with the Fresnel probability using uComponent (uDir is read but unused).
#include <cmath>

#include "common/bsdf/bsdfs.h"
#include "common/bsdf/fresnel.h"
#include "common/core/sampling_inverse.h"

namespace mlt {

namespace {

Color colorMax(const Color& a, const Color& b) { return {std::fmax(a.r, b.r), std::fmax(a.g, b.g), std::fmax(a.b, b.b)}; }

class Dielectric final : public Bsdf {
 public:
  Dielectric(float eta, TexturePtr r, TexturePtr t) : eta_(eta), specR_(std::move(r)), specT_(std::move(t)) {
    reads_.direction = false;  // two Dirac lobes, chosen by uComponent
  }

  Color eval(const Vec3&, const Vec3&, const BsdfQuery&) const override { return Color(0.0f); }
  float pdf(const Vec3&, const Vec3&, const BsdfQuery&) const override { return 0; }

  std::optional<BsdfSample> sample(const Vec3& wo, float uc, Vec2, const BsdfQuery& q) const override {
    if (wo.z == 0) return std::nullopt;
    float cosThetaT;
    const float F = fresnelDielectric(wo.z, eta_, &cosThetaT);
    BsdfSample s;
    s.delta = true;
    if (uc < F) {
      // Throughput weight f |cos| / pdf = specularReflectance.
      s.wi = reflectZ(wo);
      s.f = specR_->eval(q.uv) * (F / std::fabs(s.wi.z));
      s.pdfW = s.pdfRevW = F;
      s.eta = 1;
      return s;
    }
    s.wi = refractZ(wo, cosThetaT, eta_);
    if (s.wi.z == 0) return std::nullopt;
    // eta_t / eta_i for the crossing; radiance is scaled by (eta_i / eta_t)^2 = 1 / etaCross^2
    // (Veach 1997, eq. 5.12), in Radiance mode only.
    const float etaCross = cosThetaT < 0 ? eta_ : 1 / eta_;
    const float factor = q.mode == TransportMode::Radiance ? 1 / (etaCross * etaCross) : 1.0f;
    s.f = specT_->eval(q.uv) * ((1 - F) * factor / std::fabs(cosThetaT));
    s.pdfW = 1 - F;
    s.pdfRevW = 1 - fresnelDielectric(s.wi.z, eta_);
    s.eta = etaCross;
    return s;
  }
  // Inverse: wi decides the lobe (reflection and refraction never share a direction); uComponent is put
  // in the lobe's interval [0, F) or [F, 1) (eq. 40, Jacobian F or 1 - F); uDir is unread (gamma.fill).
  std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                const BsdfQuery&) const override {
    if (wo.z == 0) return std::nullopt;
    float cosThetaT;
    const float F = fresnelDielectric(wo.z, eta_, &cosThetaT);
    if (F > 0 && sameDeltaDirection(wi, reflectZ(wo))) return BsdfSampleInverse{invertInterval(0, F, gamma.pick), gamma.fill, F};
    if (F < 1 && sameDeltaDirection(wi, refractZ(wo, cosThetaT, eta_)))
      return BsdfSampleInverse{invertInterval(F, 1, gamma.pick), gamma.fill, 1 - F};
    return std::nullopt;
  }
  bool isDelta() const override { return true; }
  Color albedo(const Vec2& uv) const override { return colorMax(specR_->eval(uv), specT_->eval(uv)); }

 private:
  float eta_;
  TexturePtr specR_, specT_;  // specular_reflectance / _transmittance, at the hit's uv
};

}  // namespace

std::unique_ptr<Bsdf> makeDielectric(float eta, TexturePtr r, TexturePtr t) {
  return std::make_unique<Dielectric>(eta, std::move(r), std::move(t));
}

}  // namespace mlt
