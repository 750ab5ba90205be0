// Lights at infinity: the directional light (delta direction) and the constant environment.
// Both need the scene's bounding sphere (center c, radius R), given by preprocess():
//  - sampleLi puts pLight at ref + wi * 2R with nLight = -wi, so a shadow ray to it leaves the scene;
//  - sampleLe starts rays on a disk of radius R perpendicular to the travel direction, a distance R
//    "behind" the scene center (pbrt-v3): pdfPos = 1 / (pi R^2).
#include <stdexcept>

#include "common/core/sampling.h"
#include "common/emitter/light_factories.h"

namespace mlt {
namespace {

// Origin of an emitted ray travelling along w (unit) through the disk of radius R about c.
Vec3 diskOrigin(const Vec3& c, float R, const Vec3& w, Vec2 uPos) {
  const Frame f(w);
  const Vec2 d = sampleConcentricDisk(uPos);
  return c + (f.s * d.x + f.t * d.y) * R - w * R;
}

// ---- directional -------------------------------------------------------------------------------
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
  Color power() const override { return E_ * (kPi * R_ * R_); }  // flux through the scene's disk
  bool deltaDirection() const override { return true; }
  bool infinite() const override { return true; }

 private:
  Vec3 d_;   // travel direction
  Color E_;
  Vec3 c_;
  float R_ = 1;
};

// ---- constant environment ----------------------------------------------------------------------
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

std::unique_ptr<Light> makeDirectionalLight(const Vec3& d, const Color& E) {
  const float len = length(d);
  if (!(len > 0) || !std::isfinite(len)) throw std::runtime_error("directional light: direction has zero length");
  return std::make_unique<DirectionalLight>(d / len, E);
}

std::unique_ptr<Light> makeConstantEnvironment(const Color& L) { return std::make_unique<ConstantEnvironment>(L); }

}  // namespace mlt
