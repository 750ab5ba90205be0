// Isotropic point light (a delta position).
// Conventions (interfaces/light.h): sampleLi's pdfW = pdfA = 1 and L = I / dist^2 (pbrt-v3); it can never
// be hit, so pdfLi = 0; sampleLe's pdfPos = 1 and L is the intensity I.
#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"
#include "common/emitter/light_factories.h"

namespace mlt {
namespace {

class PointLight final : public Light {
 public:
  PointLight(const Vec3& p, const Color& I) : p_(p), I_(I) {}

  std::optional<LightLiSample> sampleLi(const Vec3& ref, Vec2 u) const override {
    Vec3 wi = p_ - ref;
    const float d2 = lengthSquared(wi);
    if (!(d2 > 0)) return std::nullopt;
    LightLiSample s;
    s.wi = wi / std::sqrt(d2);
    s.L = I_ / d2;
    s.pLight = p_;
    s.pdfW = s.pdfA = 1;
    s.deltaPosition = true;
    return s;
  }
  float pdfLi(const Vec3&, const Vec3&, const Vec3&, const Vec3&) const override { return 0; }
  std::optional<LightLeSample> sampleLe(Vec2 uPos, Vec2 uDir) const override {
    LightLeSample s;
    s.L = I_;
    s.ray.o = p_;
    s.ray.d = sampleUniformSphere(uDir);
    s.pdfPos = 1;
    s.pdfDir = uniformSpherePdfW();
    return s;
  }
  void pdfLe(const Vec3&, const Vec3&, const Vec3&, float* pdfPos, float* pdfDir) const override {
    *pdfPos = 1;
    *pdfDir = uniformSpherePdfW();
  }
  // Inverses (interfaces/inverse.h): the position is a delta (pdf 1), its numbers unread (gamma.fill);
  // the emitted direction is uniform on the sphere.
  std::optional<Inverse2D> invertSampleLi(const Vec3& ref, const Vec3& pLight, const Vec3&,
                                          const InverseGamma& gamma) const override {
    if (!samePoint(pLight) || !(distanceSquared(ref, p_) > 0)) return std::nullopt;
    return Inverse2D{gamma.fill, 1.0f};
  }
  std::optional<LightLeInverse> invertSampleLe(const Vec3& pLight, const Vec3&, const Vec3& w,
                                               const InverseGamma& gamma) const override {
    if (!samePoint(pLight) || !(lengthSquared(w) > 0)) return std::nullopt;
    return LightLeInverse{{gamma.fill, 1.0f}, {invertUniformSphere(normalize(w)), uniformSpherePdfW()}};
  }
  Color power() const override { return I_ * (4 * kPi); }
  bool deltaPosition() const override { return true; }

 private:
  bool samePoint(const Vec3& p) const { return distance(p, p_) <= 1e-4f * std::fmax(1.0f, length(p_)); }
  Vec3 p_;
  Color I_;
};

}  // namespace

std::unique_ptr<Light> makePointLight(const Vec3& position, const Color& I) {
  return std::make_unique<PointLight>(position, I);
}

}  // namespace mlt
