// Constant environment: radiance L arriving from every direction at infinity (infinite_disk.h for the
// conventions).
#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"
#include "common/emitter/infinite_disk.h"
#include "common/emitter/light_factories.h"

namespace mlt {
namespace {

class ConstantEnvironment final : public Light {
 public:
  explicit ConstantEnvironment(const Color& L) : L_(L) {}
  void preprocess(const Vec3& c, float R) override { c_ = c; R_ = R; }

  std::optional<LightLiSample> sampleLi(const Vec3& ref, Vec2 u) const override {
    LightLiSample s;
    s.wi = sampleUniformSphere(u);
    s.L = L_;
    s.pLight = ref + s.wi * (2 * R_);
    s.nLight = -s.wi;
    s.pdfW = s.pdfA = uniformSpherePdfW();
    s.infinite = true;
    return s;
  }
  float pdfLi(const Vec3&, const Vec3&, const Vec3&, const Vec3&) const override { return uniformSpherePdfW(); }
  std::optional<LightLeSample> sampleLe(Vec2 uPos, Vec2 uDir) const override {
    const Vec3 w = sampleUniformSphere(uDir);  // travel direction; it arrives from -w
    LightLeSample s;
    s.L = L_;
    s.ray.o = diskOrigin(c_, R_, w, uPos);
    s.ray.d = w;
    s.nLight = w;
    s.pdfPos = 1 / (kPi * R_ * R_);
    s.pdfDir = uniformSpherePdfW();
    return s;
  }
  void pdfLe(const Vec3&, const Vec3&, const Vec3&, float* pdfPos, float* pdfDir) const override {
    *pdfPos = 1 / (kPi * R_ * R_);
    *pdfDir = uniformSpherePdfW();
  }
  // Inverses (interfaces/inverse.h): sampleLi's direction is uniform on the sphere; sampleLe's direction
  // likewise and its origin a point of the disk perpendicular to it (infinite_disk.h).
  std::optional<Inverse2D> invertSampleLi(const Vec3& ref, const Vec3& pLight, const Vec3&,
                                          const InverseGamma&) const override {
    const Vec3 wi = pLight - ref;
    if (!(lengthSquared(wi) > 0)) return std::nullopt;
    return Inverse2D{invertUniformSphere(normalize(wi)), uniformSpherePdfW()};
  }
  std::optional<LightLeInverse> invertSampleLe(const Vec3& pLight, const Vec3&, const Vec3& w,
                                               const InverseGamma&) const override {
    if (!(lengthSquared(w) > 0)) return std::nullopt;
    const Vec3 wn = normalize(w);
    const std::optional<Vec2> uPos = invertDiskOrigin(c_, R_, wn, pLight);
    if (!uPos) return std::nullopt;
    return LightLeInverse{{*uPos, 1 / (kPi * R_ * R_)}, {invertUniformSphere(wn), uniformSpherePdfW()}};
  }
  Color Le(const Vec3&) const override { return L_; }
  // Flux entering the bounding sphere: pi L per unit area (cosine-weighted hemisphere) times 4 pi R^2
  // (pbrt-v4's UniformInfiniteLight::Phi); equals E[L / (pdfPos pdfDir)] of sampleLe.
  Color power() const override { return L_ * (4 * kPi * kPi * R_ * R_); }
  bool infinite() const override { return true; }

 private:
  Color L_;
  Vec3 c_;
  float R_ = 1;
};

}  // namespace

std::unique_ptr<Light> makeConstantEnvironment(const Color& L) { return std::make_unique<ConstantEnvironment>(L); }

}  // namespace mlt
