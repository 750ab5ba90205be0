// Perspective cameras: pinhole (lensRadius = 0) and thin lens, with Mitsuba's conventions and pbrt-v3's
// importance.
//
// Camera space (Mitsuba): +z forward, +y up, +x LEFT. Raster (0,0) is the top-left corner of the image,
// x to the right, y down. On the plane z = 1 the film spans x in [-tx, tx], y in [-ty, ty] with
//   x_cam = -(2 px / W - 1) tx,  y_cam = (1 - 2 py / H) ty,
// so a raster x increasing to the right is camera -x: with Mitsuba's lookat (+x = up x dir = left) the
// image is not mirrored. fovAxis picks which extent the fov spans (Mitsuba's fov_axis).
//
// Importance (pbrt-v3, sec. 16.1.1), normalized over the whole film: A = (2 tx)(2 ty) is the film area
// at z = 1, and for a ray leaving the lens at angle theta to the axis inside the frustum
//   We = 1 / (A * lensArea * cos^4 theta),  pdfPos = 1 / lensArea,  pdfDir = 1 / (A cos^3 theta),
// lensArea = pi r^2 (1 for a pinhole). Near clip: a ray starts at tMin = nearClip / cos theta, and a
// point with camera depth z < nearClip is not seen (sampleWi, rasterPosition).
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"
#include "common/camera/make_camera.h"
#include "common/scene/scene_desc.h"

namespace mlt {
namespace {

class PerspectiveCamera final : public Camera {
 public:
  explicit PerspectiveCamera(const CameraDesc& desc);

  CameraRay generateRay(Vec2 pRaster, Vec2 uLens) const override;
  Color We(const Ray& ray, Vec2* pRaster) const override;
  void pdfWe(const Ray& ray, float* pdfPos, float* pdfDir) const override;
  std::optional<CameraWiSample> sampleWi(const Vec3& ref, Vec2 uLens) const override;
  std::optional<Vec2> rasterPosition(const Vec3& p) const override;
  std::optional<CameraRayInverse> invertGenerateRay(const Ray& ray, const InverseGamma& gamma) const override;
  std::optional<Inverse2D> invertSampleWi(const Vec3& ref, const Vec3& pLens, const InverseGamma& gamma) const override;
  bool deltaPosition() const override { return lensRadius_ == 0; }

 private:
  Vec3 toWorldDir(const Vec3& v) const { return X_ * v.x + Y_ * v.y + Z_ * v.z; }
  Vec3 toCameraDir(const Vec3& v) const { return {dot(v, X_), dot(v, Y_), dot(v, Z_)}; }
  Vec3 toCameraPoint(const Vec3& p) const { return toCameraDir(p - o_); }
  // Raster position of a camera-space point (projection through the lens center); false if outside.
  bool project(const Vec3& pc, Vec2* pRaster) const;
  // The lens sample of a camera-space lens point (inverse of the concentric disk scaled by the radius);
  // nullopt if the point is not on the lens.
  std::optional<Inverse2D> invertLens(const Vec3& pLensCam, const InverseGamma& gamma) const;

  Vec3 o_, X_, Y_, Z_;  // camera position and orthonormal axes in world space (X = left)
  float tx_ = 1, ty_ = 1, A_ = 4;
  float lensRadius_ = 0, lensArea_ = 1, invLensArea_ = 1, focus_ = 1, nearClip_ = 0;
};

PerspectiveCamera::PerspectiveCamera(const CameraDesc& desc) {
  if (desc.width <= 0 || desc.height <= 0)
    throw std::runtime_error("camera: film width/height must be > 0 (got " + std::to_string(desc.width) + "x" +
                             std::to_string(desc.height) + ")");
  if (!(desc.fovDeg > 0 && desc.fovDeg < 180)) throw std::runtime_error("camera: fov must be in (0, 180) degrees");
  if (!(desc.nearClip >= 0) || !std::isfinite(desc.nearClip)) throw std::runtime_error("camera: near_clip must be >= 0");
  if (!desc.toWorld.isFinite()) throw std::runtime_error("camera: to_world is not finite");
  width_ = desc.width;
  height_ = desc.height;

  // Camera frame from to_world; Mitsuba allows rotation, translation, uniform scale and mirroring.
  o_ = desc.toWorld.point(Vec3(0, 0, 0));
  const Vec3 ax = desc.toWorld.vector(Vec3(1, 0, 0)), ay = desc.toWorld.vector(Vec3(0, 1, 0)),
             az = desc.toWorld.vector(Vec3(0, 0, 1));
  const float lx = length(ax), ly = length(ay), lz = length(az);
  if (!desc.toWorld.isSimilarity())  // the loaders check the same at load, naming the line
    throw std::runtime_error("camera: to_world must be a rotation, translation, uniform scale or mirror");
  X_ = ax / lx;
  Y_ = ay / ly;
  Z_ = az / lz;

  // Half extents of the film at z = 1 (Mitsuba's fov_axis; aspect = W / H).
  const float aspect = float(width_) / float(height_);
  const float t = std::tan(desc.fovDeg * kPi / 360);
  using Axis = CameraDesc::FovAxis;
  Axis axis = desc.fovAxis;
  if (axis == Axis::Smaller) axis = aspect > 1 ? Axis::Y : Axis::X;
  if (axis == Axis::Larger) axis = aspect > 1 ? Axis::X : Axis::Y;
  switch (axis) {
    case Axis::Y: tx_ = t * aspect; break;
    case Axis::Diagonal: tx_ = t * aspect / std::sqrt(1 + aspect * aspect); break;
    default: tx_ = t; break;
  }
  ty_ = tx_ / aspect;
  A_ = 4 * tx_ * ty_;
  nearClip_ = desc.nearClip;

  if (desc.type == CameraDesc::Type::ThinLens && desc.apertureRadius > 0) {
    if (!(desc.focusDistance > 0) || !std::isfinite(desc.focusDistance))
      throw std::runtime_error("camera: thinlens focus_distance must be > 0");
    if (!std::isfinite(desc.apertureRadius)) throw std::runtime_error("camera: thinlens aperture_radius is not finite");
    lensRadius_ = desc.apertureRadius;
    lensArea_ = kPi * lensRadius_ * lensRadius_;
    invLensArea_ = 1 / lensArea_;
    focus_ = desc.focusDistance;
  } else if (desc.type == CameraDesc::Type::ThinLens && desc.apertureRadius < 0) {
    throw std::runtime_error("camera: thinlens aperture_radius must be >= 0");
  }
}

bool PerspectiveCamera::project(const Vec3& pc, Vec2* pRaster) const {
  if (!(pc.z > 0)) return false;
  const float px = (1 - pc.x / (pc.z * tx_)) * 0.5f * float(width_);
  const float py = (1 - pc.y / (pc.z * ty_)) * 0.5f * float(height_);
  if (!(px >= 0 && px < float(width_) && py >= 0 && py < float(height_))) return false;
  if (pRaster) *pRaster = {px, py};
  return true;
}

CameraRay PerspectiveCamera::generateRay(Vec2 pRaster, Vec2 uLens) const {
  // Point on the z = 1 plane through which the pinhole ray passes.
  const Vec3 pFilm(-(2 * pRaster.x / float(width_) - 1) * tx_, (1 - 2 * pRaster.y / float(height_)) * ty_, 1);
  Vec3 pLens(0, 0, 0), dCam = normalize(pFilm);
  if (lensRadius_ > 0) {
    const Vec2 d = sampleConcentricDisk(uLens) * lensRadius_;
    pLens = Vec3(d.x, d.y, 0);
    dCam = normalize(pFilm * focus_ - pLens);  // through the point in focus on the plane z = focus
  }
  CameraRay r;
  r.ray.o = o_ + toWorldDir(pLens);
  r.ray.d = normalize(toWorldDir(dCam));
  r.ray.tMin = nearClip_ / dCam.z;
  r.n = Z_;
  r.pdfPos = invLensArea_;
  r.pdfDir = 1 / (A_ * dCam.z * dCam.z * dCam.z);  // dCam.z = cos theta: as pdfWe
  return r;
}

Color PerspectiveCamera::We(const Ray& ray, Vec2* pRaster) const {
  const Vec3 d = normalize(ray.d);
  const float cosTheta = dot(d, Z_);
  if (!(cosTheta > 0)) return {};
  // Where the ray crosses the plane in focus (z = 1 for a pinhole), projected through the lens center.
  const Vec3 pFocus = toCameraPoint(ray.o + d * (focus_ / cosTheta));
  if (!project(pFocus, pRaster)) return {};
  const float cos2 = cosTheta * cosTheta;
  return Color(1 / (A_ * lensArea_ * cos2 * cos2));
}

void PerspectiveCamera::pdfWe(const Ray& ray, float* pdfPos, float* pdfDir) const {
  *pdfPos = *pdfDir = 0;
  const Vec3 d = normalize(ray.d);
  const float cosTheta = dot(d, Z_);
  if (!(cosTheta > 0)) return;
  if (!project(toCameraPoint(ray.o + d * (focus_ / cosTheta)), nullptr)) return;
  *pdfPos = invLensArea_;
  *pdfDir = 1 / (A_ * cosTheta * cosTheta * cosTheta);
}

// pbrt-v3 PerspectiveCamera::Sample_Wi: a point on the lens, uniform by area (pdfA = 1 / lensArea,
// 1 for a pinhole), converted to solid angle at ref: pdfW = dist^2 / (|cos_lens| * lensArea).
std::optional<CameraWiSample> PerspectiveCamera::sampleWi(const Vec3& ref, Vec2 uLens) const {
  if (toCameraPoint(ref).z < nearClip_) return std::nullopt;  // in front of the near clip plane
  Vec3 pLensCam(0, 0, 0);
  if (lensRadius_ > 0) {
    const Vec2 d = sampleConcentricDisk(uLens) * lensRadius_;
    pLensCam = Vec3(d.x, d.y, 0);
  }
  CameraWiSample s;
  s.pLens = o_ + toWorldDir(pLensCam);
  s.nLens = Z_;
  Vec3 wi = s.pLens - ref;
  const float d2 = lengthSquared(wi);
  if (!(d2 > 0)) return std::nullopt;
  wi = wi / std::sqrt(d2);
  s.wi = wi;
  Ray toRef;
  toRef.o = s.pLens;
  toRef.d = -wi;
  s.We = We(toRef, &s.pRaster);
  if (s.We.isBlack()) return std::nullopt;
  s.pdfW = d2 / (absDot(s.nLens, wi) * lensArea_);
  return s;
}

std::optional<Vec2> PerspectiveCamera::rasterPosition(const Vec3& p) const {
  const Vec3 pc = toCameraPoint(p);
  if (pc.z < nearClip_) return std::nullopt;
  Vec2 r;
  if (!project(pc, &r)) return std::nullopt;
  return r;
}

// ---- Inverses (reversible-jump MLT; interfaces/inverse.h) ---------------------------------------------

std::optional<Inverse2D> PerspectiveCamera::invertLens(const Vec3& pLensCam, const InverseGamma& gamma) const {
  if (lensRadius_ == 0) {  // a pinhole reads no lens numbers; the point must be the pinhole itself
    if (!(length(pLensCam) <= 1e-4f * std::fmax(1.0f, length(o_)))) return std::nullopt;
    return Inverse2D{gamma.fill, 1.0f};
  }
  const float tol = 1e-4f * lensRadius_;
  const Vec2 d(pLensCam.x / lensRadius_, pLensCam.y / lensRadius_);
  if (!(std::fabs(pLensCam.z) <= tol) || !(d.x * d.x + d.y * d.y <= 1 + 2e-4f)) return std::nullopt;
  return Inverse2D{invertConcentricDisk(d), 1 / lensArea_};  // Jacobian: pdfPos = 1 / (pi r^2)
}

// generateRay maps pRaster to pFilm on z = 1 and, with a lens, aims from pLens at pFilm * focus. Backwards:
// the lens point gives uLens; the ray's crossing of the plane z = focus (z = 1 for a pinhole) divided by
// the focus distance is pFilm, and x_cam = -(2 px / W - 1) tx, y_cam = (1 - 2 py / H) ty give pRaster.
// jacobianRaster: pixels per steradian. The film area at z = 1 per solid angle is 1 / cos^3(theta) (for a
// thin lens too: the plane in focus scales both by focus^2), and a unit of film area is W H / A pixels,
// so |d pRaster / d w| = W H / (A cos^3 theta) = W H pdfDir.
std::optional<CameraRayInverse> PerspectiveCamera::invertGenerateRay(const Ray& ray, const InverseGamma& gamma) const {
  const Vec3 dCam = toCameraDir(normalize(ray.d));
  if (!(dCam.z > 0)) return std::nullopt;
  const Vec3 pLensCam = toCameraPoint(ray.o);
  const std::optional<Inverse2D> lens = invertLens(pLensCam, gamma);
  if (!lens) return std::nullopt;
  const float depth = lensRadius_ > 0 ? focus_ : 1.0f;
  const Vec3 pFocus = (lensRadius_ > 0 ? pLensCam : Vec3(0, 0, 0)) + dCam * (depth / dCam.z);
  const float xFilm = pFocus.x / depth, yFilm = pFocus.y / depth;
  CameraRayInverse inv;
  inv.pRaster = {(1 - xFilm / tx_) * 0.5f * float(width_), (1 - yFilm / ty_) * 0.5f * float(height_)};
  if (!(inv.pRaster.x >= 0 && inv.pRaster.x < float(width_) && inv.pRaster.y >= 0 && inv.pRaster.y < float(height_)))
    return std::nullopt;
  const float cosTheta = dCam.z / length(dCam);
  inv.jacobianRaster = float(width_) * float(height_) / (A_ * cosTheta * cosTheta * cosTheta);
  inv.lens = *lens;
  return inv;
}

std::optional<Inverse2D> PerspectiveCamera::invertSampleWi(const Vec3& ref, const Vec3& pLens,
                                                           const InverseGamma& gamma) const {
  if (toCameraPoint(ref).z < nearClip_) return std::nullopt;
  const std::optional<Inverse2D> lens = invertLens(toCameraPoint(pLens), gamma);
  if (!lens) return std::nullopt;
  Ray toRef;
  toRef.o = pLens;
  toRef.d = ref - pLens;
  if (!(lengthSquared(toRef.d) > 0)) return std::nullopt;
  if (We(toRef, nullptr).isBlack()) return std::nullopt;  // sampleWi would not return this lens point
  return lens;
}

}  // namespace

std::unique_ptr<Camera> makeCamera(const CameraDesc& desc) { return std::make_unique<PerspectiveCamera>(desc); }

}  // namespace mlt
