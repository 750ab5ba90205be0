// Emitters: area lights on meshes, point, spot, directional and constant (environment) lights.
// Densities carry their measure: pdfA (area, on the light), pdfW (solid angle), and for lights with a
// delta position or direction the "pdf" of the delta part is 1 and the flag says so.
//
// Interface only: the concrete lights, makeLight and the LightSampler live in common/emitter/.
#pragma once
#include <optional>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/interfaces/interaction.h"
#include "common/interfaces/inverse.h"

namespace mlt {

struct LightLiSample {     // next-event estimation: a point on the light as seen from a reference point
  Color L;                 // radiance arriving at the reference point along -wi (no visibility)
  Vec3 wi;                 // unit direction from the reference point toward the light
  Vec3 pLight;             // point on the light (for infinite lights: ref + wi * 2 * sceneRadius)
  Vec3 nLight;             // light surface normal at pLight (zero for point/spot; -wi for infinite)
  Vec2 uv;                 // area lights: the surface uv at pLight (what L() takes), so a textured radiance agrees
  float pdfW = 0;          // solid-angle density of wi at the reference point (1 for delta lights)
  float pdfA = 0;          // area density of pLight (1 for delta position); for infinite lights: pdfW
  bool deltaPosition = false;
  bool infinite = false;
  bool unoccluded = false; // sampleLiVisible traced the segment ref - pLight and found it free: no shadow ray
};

struct LightLeSample {     // emission: a ray leaving the light (light subpath start)
  Color L;                 // emitted radiance along the ray (intensity for point/spot)
  Ray ray;                 // o = the exact point on the light (the vertex); area lights set tMin > 0 to
                           // skip their own surface, so the ray can be traced as is
  Vec3 nLight;             // zero for point/spot
  Vec2 uv;                 // area lights: the surface uv at ray.o (what L() takes)
  float pdfPos = 0;        // pdfA of the origin (1 for delta position; for infinite lights the pdf of the
                           // point on the disk perpendicular to the direction, 1 / (pi R^2))
  float pdfDir = 0;        // pdfW of the direction (1 for delta direction)
};

// Inverse of sampleLe() (reversible-jump MLT, see common/interfaces/inverse.h).
struct LightLeInverse {
  Inverse2D pos;           // uPos; jacobian = pdfPos of the origin (per unit area; infinite lights: on the disk)
  Inverse2D dir;           // uDir; jacobian = pdfDir of the direction (per unit solid angle)
};

// A light's own surface as a ray target: the closest hit of a ray against that light's mesh alone, no
// other geometry (the render layer implements it over Embree). A convex area light uses it to turn a
// direction sampled in the cone it subtends into the point it sees (area_light.cpp).
class EmitterSurface {
 public:
  virtual ~EmitterSurface() = default;
  virtual std::optional<SurfaceHit> intersect(const Ray& ray) const = 0;
  // The closest hit of `ray` among all the scene's surfaces if it lies on this light's mesh, else nullopt
  // (another surface comes first, or nothing is hit): one ray that finds the light's point and tests its
  // visibility together.
  virtual std::optional<SurfaceHit> firstInScene(const Ray& ray) const = 0;
};

class Light {
 public:
  virtual ~Light() = default;
  // Called once after the scene is built; infinite lights need the scene's bounding sphere.
  virtual void preprocess(const Vec3& sceneCenter, float sceneRadius) { (void)sceneCenter; (void)sceneRadius; }
  // Consumes 2 numbers.
  virtual std::optional<LightLiSample> sampleLi(const Vec3& ref, Vec2 u) const = 0;
  // sampleLi from a point on a surface with geometric normal ng (zero: on no surface), for a caller that
  // would next trace a shadow ray to the sample. A light that can (a convex area light's cone) finds its
  // point and tests that segment with one ray through the scene: it returns nullopt for a blocked sample
  // and sets `unoccluded` on the sample it returns. The same numbers, points and densities as sampleLi.
  virtual std::optional<LightLiSample> sampleLiVisible(const Vec3& ref, const Vec3& ng, Vec2 u) const {
    (void)ng;
    return sampleLi(ref, u);
  }
  // Solid-angle density with which sampleLi(ref) picks direction wi hitting pLight with normal nLight.
  virtual float pdfLi(const Vec3& ref, const Vec3& pLight, const Vec3& nLight, const Vec3& wi) const = 0;
  // Inverse of sampleLi(ref): the u with which it returns pLight (normal nLight); jacobian = the pdfA it
  // reports (infinite lights: pdfW of the direction; delta lights: 1, u = gamma.fill, which they do not
  // read). nullopt: no inverse (the default) or pLight cannot be sampled.
  virtual std::optional<Inverse2D> invertSampleLi(const Vec3& ref, const Vec3& pLight, const Vec3& nLight,
                                                  const InverseGamma& gamma) const {
    (void)ref; (void)pLight; (void)nLight; (void)gamma;
    return std::nullopt;
  }
  // Consumes 4 numbers: uPos (2), uDir (2).
  virtual std::optional<LightLeSample> sampleLe(Vec2 uPos, Vec2 uDir) const = 0;
  // Inverse of sampleLe(): the (uPos, uDir) with which it emits a ray from pLight (normal nLight) in
  // direction w. Same conventions as invertSampleLi (an unread uPos or uDir is gamma.fill, Jacobian 1).
  virtual std::optional<LightLeInverse> invertSampleLe(const Vec3& pLight, const Vec3& nLight, const Vec3& w,
                                                       const InverseGamma& gamma) const {
    (void)pLight; (void)nLight; (void)w; (void)gamma;
    return std::nullopt;
  }
  // sampleLi's density of pLight from ref per unit area (solid-angle pdfLi times cos / d^2) over sampleLe's
  // pdfPos of the same point: what bdpt's MIS weight multiplies the strategy s = 1's density by, when
  // a light samples the point it is seen from differently from the point it emits from (a convex area
  // light's cone). Exactly 1 for every light that samples both the same way (the default).
  virtual float pdfLiOverPdfPos(const Vec3& ref, const Vec3& pLight, const Vec3& nLight) const {
    (void)ref; (void)pLight; (void)nLight;
    return 1.0f;
  }
  // Whether pdfLiOverPdfPos can differ from 1 (so that bdpt's MIS weight skips the call for every other
  // light: it is made for each strategy of every sample).
  bool liDensityDiffers() const { return liDensityDiffers_; }
  // Densities of an emitted ray leaving pLight (normal nLight) in direction w.
  virtual void pdfLe(const Vec3& pLight, const Vec3& nLight, const Vec3& w, float* pdfPos, float* pdfDir) const = 0;
  // Area lights: radiance leaving a point with normal n in direction w (0 on the back side).
  virtual Color L(const Vec3& p, const Vec3& n, const Vec2& uv, const Vec3& w) const {
    (void)p; (void)n; (void)uv; (void)w; return {};
  }
  // Infinite lights: radiance arriving along a ray that left the scene in direction d.
  virtual Color Le(const Vec3& d) const { (void)d; return {}; }
  virtual Color power() const = 0;   // total emitted power (W), for light selection
  virtual bool deltaPosition() const { return false; }
  virtual bool deltaDirection() const { return false; }
  virtual bool infinite() const { return false; }

 protected:
  bool liDensityDiffers_ = false;  // set by a light whose sampleLi samples its point otherwise than sampleLe
};

}  // namespace mlt
