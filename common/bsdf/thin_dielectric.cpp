// Thin dielectric slab (Mitsuba's `thindielectric`). A pure Dirac BSDF: eval/pdf are 0, sample() picks
// reflection or straight transmission with the slab's probabilities using uComponent (uDir is unused).
#include <cmath>

#include "common/bsdf/bsdfs.h"
#include "common/bsdf/fresnel.h"
#include "common/core/sampling_inverse.h"

namespace mlt {

namespace {

Color colorMax(const Color& a, const Color& b) { return {std::fmax(a.r, b.r), std::fmax(a.g, b.g), std::fmax(a.b, b.b)}; }

// Mitsuba's thin dielectric: a slab whose two interfaces are parallel; the infinite series of internal
// reflections gives R' = R + T^2 R / (1 - R^2) and T' = 1 - R', with transmission straight through.
class ThinDielectric final : public Bsdf {
 public:
  ThinDielectric(float eta, TexturePtr r, TexturePtr t) : eta_(eta), specR_(std::move(r)), specT_(std::move(t)) {
    reads_.direction = false;  // two Dirac lobes, chosen by uComponent
  }

  Color eval(const Vec3&, const Vec3&, const BsdfQuery&) const override { return Color(0.0f); }
  float pdf(const Vec3&, const Vec3&, const BsdfQuery&) const override { return 0; }

  std::optional<BsdfSample> sample(const Vec3& wo, float uc, Vec2, const BsdfQuery& q) const override {
    if (wo.z == 0) return std::nullopt;
    const float R = slabReflectance(std::fabs(wo.z)), T = 1 - R;
    BsdfSample s;
    s.delta = true;
    s.eta = 1;
    if (uc < R) {
      s.wi = reflectZ(wo);
      s.f = specR_->eval(q.uv) * (R / std::fabs(wo.z));
      s.pdfW = s.pdfRevW = R;
    } else {
      s.wi = -wo;
      s.f = specT_->eval(q.uv) * (T / std::fabs(wo.z));
      s.pdfW = s.pdfRevW = T;
    }
    return s;
  }
  // Inverse: reflection [0, R) or straight transmission [R, 1) (eq. 40); uDir unread (gamma.fill).
  std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                const BsdfQuery&) const override {
    if (wo.z == 0) return std::nullopt;
    const float R = slabReflectance(std::fabs(wo.z)), T = 1 - R;
    if (R > 0 && sameDeltaDirection(wi, reflectZ(wo))) return BsdfSampleInverse{invertInterval(0, R, gamma.pick), gamma.fill, R};
    if (T > 0 && sameDeltaDirection(wi, -wo)) return BsdfSampleInverse{invertInterval(R, 1, gamma.pick), gamma.fill, T};
    return std::nullopt;
  }
  bool isDelta() const override { return true; }
  Color albedo(const Vec2& uv) const override { return colorMax(specR_->eval(uv), specT_->eval(uv)); }

  float slabReflectance(float absCos) const {
    float R = fresnelDielectric(absCos, eta_);
    const float T = 1 - R;
    if (R < 1) R += T * T * R / (1 - R * R);
    return R;
  }

 private:
  float eta_;
  TexturePtr specR_, specT_;  // at the hit's uv
};

}  // namespace

std::unique_ptr<Bsdf> makeThinDielectric(float eta, TexturePtr r, TexturePtr t) {
  return std::make_unique<ThinDielectric>(eta, std::move(r), std::move(t));
}

}  // namespace mlt
