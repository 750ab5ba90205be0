// The camera placement rule shared by the scene front ends (see camera_transform.h).
#include "common/scene/camera_transform.h"

namespace mlt {

std::string lookAtProblem(const Vec3& origin, const Vec3& target, const Vec3& up) {
  if (!isFinite(origin) || !isFinite(target) || !isFinite(up)) return "origin, target and up must be finite";
  const Vec3 d = target - origin;
  if (!(length(d) > 0)) return "origin and target coincide";
  if (!(length(cross(up, d)) > 0)) return "'up' is zero or parallel to the viewing direction";
  return "";
}

std::string cameraTransformProblem(const Transform& cameraToWorld) {
  if (!cameraToWorld.isFinite()) return "is not finite";
  if (!cameraToWorld.isSimilarity())
    return "must be a rotation, translation, uniform scale or mirror (this one is singular, sheared or scales "
           "the axes unequally)";
  return "";
}

}  // namespace mlt
