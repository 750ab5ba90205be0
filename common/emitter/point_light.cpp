// Isotropic point light (a delta position).
// Conventions (interfaces/light.h): sampleLi's pdfW = pdfA = 1 and L = I / dist^2 (pbrt-v3); it can never
// be hit, so pdfLi = 0; sampleLe's pdfPos = 1 and L is the intensity I.
#include "common/core/sampling.h"
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
  Color power() const override { return I_ * (4 * kPi); }
  bool deltaPosition() const override { return true; }

 private:
  Vec3 p_;
  Color I_;
};

}  // namespace

std::unique_ptr<Light> makePointLight(const Vec3& position, const Color& I) {
  return std::make_unique<PointLight>(position, I);
}

}  // namespace mlt
