// BSDF interface. Directions are in the local shading frame (z = shading normal), both pointing away
// from the surface: wo toward the previous vertex (the camera side for radiance transport), wi the
// sampled one. Values f exclude the cosine factor.
//
// Transport mode: radiance (paths traced from the camera) or importance (traced from lights). The only
// BSDF-level difference is refraction's 1/eta^2 radiance scaling (Veach 1997, sec. 5.2), applied in
// Radiance mode only. The shading-normal correction for importance transport (Veach 1997, eq. 5.19)
// depends on the geometric normal and is applied by the integrators (see shadingNormalCorrection).
//
// Interface only: the concrete BSDFs and makeBsdf live in common/bsdf/ (make_bsdf.h).
#pragma once
#include <cmath>
#include <optional>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/interfaces/inverse.h"

namespace mlt {

enum class TransportMode { Radiance, Importance };

struct BsdfSample {  // what sample() returns
  Vec3 wi;
  Color f;            // BSDF value for (wo, wi); for a delta component the weight such that f*|cos|/pdfW is the throughput
  float pdfW = 0;     // solid-angle density of wi given wo (component choice included); for delta: the discrete probability
  float pdfRevW = 0;  // density of sampling wo given wi (needed by BDPT's MIS)
  bool delta = false; // sampled from a Dirac component
  float eta = 1;      // relative IOR crossed (1 for reflection)
};

// Inverse of sample() (reversible-jump MLT, see common/interfaces/inverse.h): the primary numbers
// (uComponent, uDir) with which sample(wo, uComponent, uDir, q) returns wi.
struct BsdfSampleInverse {
  float uComponent = 0;
  Vec2 uDir;
  float jacobian = 0;  // |det du / d(wi)|, i.e. the pdfW sample() reports for wi (per unit solid angle,
                       // component choice included; for a delta component its discrete probability)
};

// Evaluation context: the texture coordinate is all a BSDF may look at besides directions.
struct BsdfQuery {
  Vec2 uv;
  TransportMode mode = TransportMode::Radiance;
};

// 1 - cos of the largest angle between a given direction and a Dirac lobe's direction that still counts as
// that lobe (about 4.5e-3 rad): a path turned back into numbers carries rounding from its vertex positions.
constexpr float kDeltaDirectionTolerance = 1e-5f;
inline bool sameDeltaDirection(const Vec3& a, const Vec3& b) {
  return dot(a, b) >= (1 - kDeltaDirectionTolerance) * std::sqrt(dot(a, a) * dot(b, b));
}

// Which of sample()'s numbers a BSDF reads: a single lobe needs no uComponent, a Dirac lobe (a mirror,
// smooth glass) no uDir. The path samplers read only these (readBsdfNumbers, integrators/bsdf_numbers.h),
// so a Markov chain over primary samples neither mutates nor backs up numbers no path depends on; the
// block layout of the sample vector (sampler/sample_source.h) is the same either way.
struct BsdfReads {
  bool component = true;  // uComponent
  bool direction = true;  // uDir
};

class Bsdf {
 public:
  virtual ~Bsdf() = default;
  // sample() returns the same for any value of a number this says it does not read (bsdf_test:
  // BsdfReads.UnreadNumbersDoNotChangeTheSample).
  BsdfReads reads() const { return reads_; }
  // f(wo, wi) of the non-delta components; 0 when only delta components could connect the two.
  virtual Color eval(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const = 0;
  // Solid-angle density with which sample() produces wi given wo, non-delta components only
  // (including the probability of choosing those components).
  virtual float pdf(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const = 0;
  // Takes kBsdfDims - 1 = 3 numbers: uComponent then uDir (2D), of which it reads those reads() names.
  // nullopt = absorbed.
  virtual std::optional<BsdfSample> sample(const Vec3& wo, float uComponent, Vec2 uDir, const BsdfQuery& q) const = 0;
  // Inverse of sample(): the primary numbers that produce wi given wo, or nullopt when this BSDF has no
  // inverse (the default) or sample() cannot produce wi. gamma.pick chooses the component by T(t) of
  // eq. 44 where several could have produced wi, then uComponent inside its interval (eq. 40);
  // gamma.fill becomes uDir where the chosen component does not read it (Dirac components).
  // A Dirac direction is matched within kDeltaDirectionTolerance.
  virtual std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                        const BsdfQuery& q) const {
    (void)wo; (void)wi; (void)gamma; (void)q;
    return std::nullopt;
  }
  // True if every component is a Dirac delta (mirror, glass): such a vertex cannot be connected to.
  virtual bool isDelta() const = 0;
  // Hemispherical albedo estimate for the given wo, used for Russian roulette hints only.
  virtual Color albedo(const Vec2& uv) const = 0;

 protected:
  BsdfReads reads_;  // set by the constructor of a BSDF that reads fewer than all three
};

// Shading-normal correction for importance transport (Veach 1997, eq. 5.19):
// |wo . ns| |wi . ng| / (|wo . ng| |wi . ns|), all in world space.
inline float shadingNormalCorrection(const Vec3& woW, const Vec3& wiW, const Vec3& ng, const Vec3& ns) {
  const float num = std::fabs(dot(woW, ns)) * std::fabs(dot(wiW, ng));
  const float den = std::fabs(dot(woW, ng)) * std::fabs(dot(wiW, ns));
  return den > 0 ? num / den : 0.0f;
}

}  // namespace mlt
