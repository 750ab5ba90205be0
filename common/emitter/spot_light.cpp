// The spot light (a delta position) of Mitsuba and of pbrt-v3 (light_factories.h: the falloff curves).
// Conventions (interfaces/light.h): sampleLi's pdfW = pdfA = 1 and L = I(w) / dist^2 (pbrt-v3); it can
// never be hit, so pdfLi = 0; sampleLe's pdfPos = 1 and L is the intensity in the sampled direction.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"
#include "common/emitter/light_factories.h"

namespace mlt {
namespace {

class SpotLight final : public Light {
 public:
  SpotLight(const Vec3& p, const Vec3& axis, const Color& I, float cutoffDeg, float beamDeg, SpotFalloffCurve curve)
      : p_(p), frame_(axis), I_(I), curve_(curve) {
    cutoff_ = cutoffDeg * kPi / 180;
    beam_ = beamDeg * kPi / 180;
    cosCutoff_ = std::cos(cutoff_);
    cosBeam_ = std::cos(beam_);
  }

  // 1 inside the beam, 0 beyond the cutoff (continuous, monotone in theta); in the transition
  // Mitsuba: (cutoff - theta) / (cutoff - beam); pbrt-v3: delta^4, delta = (cos theta - cos cutoff) /
  // (cos beam - cos cutoff) (pbrt-v3 SpotLight::Falloff).
  float falloff(float cosTheta) const {
    if (cosTheta <= cosCutoff_) return 0;
    if (cosTheta >= cosBeam_) return 1;
    if (curve_ == SpotFalloffCurve::PbrtQuartic) {
      const float delta = std::clamp((cosTheta - cosCutoff_) / (cosBeam_ - cosCutoff_), 0.0f, 1.0f);
      return (delta * delta) * (delta * delta);
    }
    const float theta = std::acos(std::clamp(cosTheta, -1.0f, 1.0f));
    return std::clamp((cutoff_ - theta) / (cutoff_ - beam_), 0.0f, 1.0f);
  }

  std::optional<LightLiSample> sampleLi(const Vec3& ref, Vec2 u) const override {
    Vec3 wi = p_ - ref;
    const float d2 = lengthSquared(wi);
    if (!(d2 > 0)) return std::nullopt;
    LightLiSample s;
    s.wi = wi / std::sqrt(d2);
    s.L = I_ * (falloff(-dot(s.wi, frame_.n)) / d2);
    s.pLight = p_;
    s.pdfW = s.pdfA = 1;
    s.deltaPosition = true;
    return s;
  }
  float pdfLi(const Vec3&, const Vec3&, const Vec3&, const Vec3&) const override { return 0; }
  // Directions uniform in the cutoff cone.
  std::optional<LightLeSample> sampleLe(Vec2 uPos, Vec2 uDir) const override {
    const Vec3 local = sampleUniformCone(uDir, cosCutoff_);
    LightLeSample s;
    s.L = I_ * falloff(local.z);
    s.ray.o = p_;
    s.ray.d = normalize(frame_.toWorld(local));
    s.pdfPos = 1;
    s.pdfDir = uniformConePdfW(cosCutoff_);
    return s;
  }
  void pdfLe(const Vec3&, const Vec3&, const Vec3& w, float* pdfPos, float* pdfDir) const override {
    *pdfPos = 1;
    *pdfDir = dot(w, frame_.n) > cosCutoff_ ? uniformConePdfW(cosCutoff_) : 0.0f;
  }
  // Inverses (interfaces/inverse.h): delta position (gamma.fill, pdf 1); directions uniform in the cone.
  std::optional<Inverse2D> invertSampleLi(const Vec3& ref, const Vec3& pLight, const Vec3&,
                                          const InverseGamma& gamma) const override {
    if (!samePoint(pLight) || !(distanceSquared(ref, p_) > 0)) return std::nullopt;
    return Inverse2D{gamma.fill, 1.0f};
  }
  std::optional<LightLeInverse> invertSampleLe(const Vec3& pLight, const Vec3&, const Vec3& w,
                                               const InverseGamma& gamma) const override {
    if (!samePoint(pLight) || !(lengthSquared(w) > 0)) return std::nullopt;
    const Vec3 local = frame_.toLocal(normalize(w));
    if (!(local.z > cosCutoff_)) return std::nullopt;
    return LightLeInverse{{gamma.fill, 1.0f}, {invertUniformCone(local, cosCutoff_), uniformConePdfW(cosCutoff_)}};
  }
  // Phi = 2 pi I int_0^c f(theta) sin(theta) dtheta. With f linear in theta between beam b and cutoff c:
  //     = 2 pi I (1 - (sin c - sin b) / (c - b))   (-> 2 pi I (1 - cos c) as b -> c);
  // pbrt's, substituting x = cos theta: 2 pi I ((1 - cos b) + int_(cos c)^(cos b) delta(x)^4 dx)
  //     = 2 pi I ((1 - cos b) + (cos b - cos c) / 5).
  Color power() const override {
    if (curve_ == SpotFalloffCurve::PbrtQuartic) return I_ * (2 * kPi * ((1 - cosBeam_) + (cosBeam_ - cosCutoff_) / 5));
    const float w = cutoff_ - beam_;
    const float integral = w > 1e-4f ? 1 - (std::sin(cutoff_) - std::sin(beam_)) / w : 1 - std::cos(cutoff_);
    return I_ * (2 * kPi * integral);
  }
  bool deltaPosition() const override { return true; }

 private:
  bool samePoint(const Vec3& p) const { return distance(p, p_) <= 1e-4f * std::fmax(1.0f, length(p_)); }
  Vec3 p_;
  Frame frame_;
  Color I_;
  SpotFalloffCurve curve_;
  float cutoff_, beam_, cosCutoff_, cosBeam_;
};

}  // namespace

std::unique_ptr<Light> makeSpotLight(const Vec3& position, const Vec3& axis, const Color& I, float cutoffDeg,
                                     float beamWidthDeg, SpotFalloffCurve curve) {
  if (!(cutoffDeg > 0 && cutoffDeg < 180))
    throw std::runtime_error("spot light: cutoff_angle must be in (0, 180) degrees");
  if (!(beamWidthDeg >= 0)) throw std::runtime_error("spot light: beam_width must be >= 0 degrees");
  if (beamWidthDeg > cutoffDeg)  // Mitsuba asserts cutoff_angle >= beam_width
    throw std::runtime_error("spot light: beam_width (" + std::to_string(beamWidthDeg) + ") exceeds cutoff_angle (" +
                             std::to_string(cutoffDeg) + ")");
  const float len = length(axis);
  if (!(len > 0) || !std::isfinite(len)) throw std::runtime_error("spot light: direction has zero length");
  return std::make_unique<SpotLight>(position, axis / len, I, cutoffDeg, beamWidthDeg, curve);
}

}  // namespace mlt
