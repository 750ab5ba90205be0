// Lambertian reflection (Mitsuba's `diffuse`).
#include "common/bsdf/bsdfs.h"
#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"

namespace mlt {

namespace {

class Diffuse final : public Bsdf {
 public:
  explicit Diffuse(TexturePtr rho) : rho_(std::move(rho)) { reads_.component = false; }

  Color eval(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const override {
    if (wo.z <= 0 || wi.z <= 0) return Color(0.0f);
    return rho_->eval(q.uv) * kInvPi;
  }
  float pdf(const Vec3& wo, const Vec3& wi, const BsdfQuery&) const override {
    if (wo.z <= 0 || wi.z <= 0) return 0;
    return cosineHemispherePdfW(wi.z);
  }
  std::optional<BsdfSample> sample(const Vec3& wo, float, Vec2 uDir, const BsdfQuery& q) const override {
    if (wo.z <= 0) return std::nullopt;
    BsdfSample s;
    s.wi = sampleCosineHemisphere(uDir);
    if (s.wi.z <= 0) return std::nullopt;  // measure-zero grazing sample
    s.f = rho_->eval(q.uv) * kInvPi;
    s.pdfW = cosineHemispherePdfW(s.wi.z);
    s.pdfRevW = cosineHemispherePdfW(wo.z);
    return s;
  }
  // Inverse: uComponent is not read (gamma.pick); uDir inverts the cosine-weighted hemisphere.
  std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                const BsdfQuery&) const override {
    if (wo.z <= 0 || wi.z <= 0) return std::nullopt;
    return BsdfSampleInverse{clampPrimary(gamma.pick), invertCosineHemisphere(wi), cosineHemispherePdfW(wi.z)};
  }
  bool isDelta() const override { return false; }
  Color albedo(const Vec2& uv) const override { return rho_->eval(uv); }

 private:
  TexturePtr rho_;
};

}  // namespace

std::unique_ptr<Bsdf> makeDiffuse(TexturePtr reflectance) { return std::make_unique<Diffuse>(std::move(reflectance)); }

}  // namespace mlt
