// Directional light: a light at infinity with a delta direction (infinite_disk.h for the conventions).
#include <cmath>
#include <stdexcept>

#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"
#include "common/emitter/infinite_disk.h"
#include "common/emitter/light_factories.h"

namespace mlt {
namespace {

class DirectionalLight final : public Light {
 public:
  DirectionalLight(const Vec3& d, const Color& E) : d_(d), E_(E) {}
  void preprocess(const Vec3& c, float R) override { c_ = c; R_ = R; }

  std::optional<LightLiSample> sampleLi(const Vec3& ref, Vec2 u) const override {
    LightLiSample s;
    s.L = E_;
    s.wi = -d_;
    s.pLight = ref + s.wi * (2 * R_);
    s.nLight = d_;
    s.pdfW = s.pdfA = 1;
    s.infinite = true;
    return s;
  }
  float pdfLi(const Vec3&, const Vec3&, const Vec3&, const Vec3&) const override { return 0; }
  std::optional<LightLeSample> sampleLe(Vec2 uPos, Vec2 uDir) const override {
    LightLeSample s;
    s.L = E_;
    s.ray.o = diskOrigin(c_, R_, d_, uPos);
    s.ray.d = d_;
    s.nLight = d_;
    s.pdfPos = 1 / (kPi * R_ * R_);
    s.pdfDir = 1;
    return s;
  }
  void pdfLe(const Vec3&, const Vec3&, const Vec3&, float* pdfPos, float* pdfDir) const override {
    *pdfPos = 1 / (kPi * R_ * R_);
    *pdfDir = 0;
  }
  // Inverses (interfaces/inverse.h): sampleLi reads no numbers (gamma.fill, pdf 1) and only returns the
  // direction -d; sampleLe's origin is a point of the disk (infinite_disk.h), its direction a delta.
  std::optional<Inverse2D> invertSampleLi(const Vec3& ref, const Vec3& pLight, const Vec3&,
                                          const InverseGamma& gamma) const override {
    const Vec3 wi = pLight - ref;
    if (!(lengthSquared(wi) > 0) || !sameDirection(-normalize(wi))) return std::nullopt;
    return Inverse2D{gamma.fill, 1.0f};
  }
  std::optional<LightLeInverse> invertSampleLe(const Vec3& pLight, const Vec3&, const Vec3& w,
                                               const InverseGamma& gamma) const override {
    if (!(lengthSquared(w) > 0) || !sameDirection(normalize(w))) return std::nullopt;
    const std::optional<Vec2> uPos = invertDiskOrigin(c_, R_, d_, pLight);
    if (!uPos) return std::nullopt;
    return LightLeInverse{{*uPos, 1 / (kPi * R_ * R_)}, {gamma.fill, 1.0f}};
  }
  Color power() const override { return E_ * (kPi * R_ * R_); }  // flux through the scene's disk
  bool deltaDirection() const override { return true; }
  bool infinite() const override { return true; }

 private:
  bool sameDirection(const Vec3& w) const { return dot(w, d_) >= 1 - 1e-5f; }
  Vec3 d_;   // travel direction
  Color E_;
  Vec3 c_;
  float R_ = 1;
};

}  // namespace

std::unique_ptr<Light> makeDirectionalLight(const Vec3& d, const Color& E) {
  const float len = length(d);
  if (!(len > 0) || !std::isfinite(len)) throw std::runtime_error("directional light: direction has zero length");
  return std::make_unique<DirectionalLight>(d / len, E);
}

}  // namespace mlt
