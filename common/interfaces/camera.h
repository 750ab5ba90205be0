// Cameras: pinhole perspective and thin lens. Importance We is normalized over the whole film
// (pbrt-v3 convention): the film plane at distance 1 has area A, and We = 1 / (A * lensArea * cos^4(theta))
// for a direction inside the film frustum. A pixel's measurement is then P * E[...] where P is the
// pixel count; film development applies that factor (see film/film.h), never the camera.
//
// Interface only: the perspective / thin-lens camera and makeCamera live in common/camera/.
#pragma once
#include <optional>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/interfaces/interaction.h"
#include "common/interfaces/inverse.h"

namespace mlt {

struct CameraRay {
  Ray ray;               // unit direction
  Vec3 n;                // camera forward axis (the "normal" of the lens)
  // pdfWe(ray) as generateRay knows it (from the direction in camera space, no projection back onto the
  // film): the same densities up to rounding, without a second pass over the ray. Both 0 if no ray.
  float pdfPos = 0, pdfDir = 0;
};

struct CameraWiSample {  // BDPT t=1 / light tracing: connect a point to the lens
  Color We;              // importance arriving at the lens from ref
  Vec3 wi;               // unit, from ref toward the lens point
  Vec3 pLens;
  Vec3 nLens;            // camera forward axis
  float pdfW = 0;        // solid-angle density at ref of choosing pLens (pbrt-v3 Sample_Wi): dist^2 / (|cos| lensArea),
                         // lensArea = 1 for a pinhole (its delta position has pdfA 1); contribution = We f |cos_ref| / pdfW
  Vec2 pRaster;          // where the path lands on the film, in pixels ([0,W) x [0,H))
};

// Inverse of generateRay() (reversible-jump MLT, see common/interfaces/inverse.h): the raster position
// and lens sample of a primary ray. The integrator maps primary numbers to pRaster (u * (W, H)).
struct CameraRayInverse {
  Vec2 pRaster;              // pixels, as generateRay takes it
  float jacobianRaster = 0;  // |det d(pRaster) / d(w)|: pixels per unit solid angle of the direction
  Inverse2D lens;            // uLens; jacobian = pdfPos of the lens point (per unit area; 1 for a pinhole)
};

class Camera {
 public:
  virtual ~Camera() = default;
  int width() const { return width_; }
  int height() const { return height_; }
  // pRaster in pixels, (0,0) = top-left corner of the film; uLens in [0,1)^2. Consumes nothing itself.
  virtual CameraRay generateRay(Vec2 pRaster, Vec2 uLens) const = 0;
  // Inverse of generateRay(): the (pRaster, uLens) that generate `ray` (o on the lens, d unit), or
  // nullopt: no inverse (the default) or the ray misses the film. A pinhole does not read uLens: it is
  // gamma.fill with Jacobian 1.
  virtual std::optional<CameraRayInverse> invertGenerateRay(const Ray& ray, const InverseGamma& gamma) const {
    (void)ray; (void)gamma;
    return std::nullopt;
  }
  // Importance for a ray leaving the lens at ray.o in direction ray.d; sets *pRaster if the ray hits the
  // film. Zero outside the frustum.
  virtual Color We(const Ray& ray, Vec2* pRaster) const = 0;
  // pdfPos (area on the lens; 1 for a pinhole) and pdfDir (solid angle) of a generated ray.
  virtual void pdfWe(const Ray& ray, float* pdfPos, float* pdfDir) const = 0;
  // Consumes 2 numbers (uLens); nullopt if ref is not visible on the film.
  virtual std::optional<CameraWiSample> sampleWi(const Vec3& ref, Vec2 uLens) const = 0;
  // Inverse of sampleWi(ref): the uLens with which it picks pLens; jacobian = pdfPos of pLens (per unit
  // lens area). A pinhole does not read uLens: gamma.fill, Jacobian 1 (its pdfPos). nullopt: no inverse
  // (the default), pLens not on the lens, or ref not visible.
  virtual std::optional<Inverse2D> invertSampleWi(const Vec3& ref, const Vec3& pLens, const InverseGamma& gamma) const {
    (void)ref; (void)pLens; (void)gamma;
    return std::nullopt;
  }
  // Raster position of a world point, if it lands on the film (pinhole projection through the lens center).
  virtual std::optional<Vec2> rasterPosition(const Vec3& p) const = 0;
  virtual bool deltaPosition() const = 0;  // pinhole

 protected:
  int width_ = 0, height_ = 0;
};

}  // namespace mlt
