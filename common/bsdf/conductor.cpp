// Smooth metal (Mitsuba's `conductor`): a Dirac reflection weighted by the exact conductor Fresnel term.
// One-sided, as in Mitsuba: absorbed when wo is on the back.
#include <cmath>

#include "common/bsdf/bsdfs.h"
#include "common/bsdf/fresnel.h"
#include "common/core/sampling_inverse.h"

namespace mlt {

namespace {

class Conductor final : public Bsdf {
 public:
  Conductor(Color eta, Color k, bool mirror, TexturePtr r) : eta_(eta), k_(k), mirror_(mirror), specR_(std::move(r)) {
    reads_ = {false, false};  // one Dirac lobe
  }

  Color eval(const Vec3&, const Vec3&, const BsdfQuery&) const override { return Color(0.0f); }
  float pdf(const Vec3&, const Vec3&, const BsdfQuery&) const override { return 0; }
  std::optional<BsdfSample> sample(const Vec3& wo, float, Vec2, const BsdfQuery& q) const override {
    if (wo.z <= 0) return std::nullopt;
    BsdfSample s;
    s.wi = reflectZ(wo);
    s.f = specR_->eval(q.uv) * fresnel(wo.z) / wo.z;
    s.pdfW = s.pdfRevW = 1;
    s.delta = true;
    return s;
  }
  // Inverse: a single Dirac lobe reads no numbers: uComponent = gamma.pick, uDir = gamma.fill, Jacobian 1.
  std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                const BsdfQuery&) const override {
    if (wo.z <= 0 || !sameDeltaDirection(wi, reflectZ(wo))) return std::nullopt;
    return BsdfSampleInverse{clampPrimary(gamma.pick), gamma.fill, 1.0f};
  }
  bool isDelta() const override { return true; }
  Color albedo(const Vec2& uv) const override { return specR_->eval(uv) * fresnel(1); }

 private:
  Color fresnel(float c) const { return mirror_ ? Color(1.0f) : fresnelConductor(c, eta_, k_); }
  Color eta_, k_;
  bool mirror_;
  TexturePtr specR_;  // specular_reflectance, at the hit's uv
};

}  // namespace

std::unique_ptr<Bsdf> makeConductor(Color eta, Color k, bool mirror, TexturePtr r) {
  return std::make_unique<Conductor>(eta, k, mirror, std::move(r));
}

}  // namespace mlt
