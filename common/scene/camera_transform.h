// The rule a camera's placement obeys in every front end (a Mitsuba sensor's to_world and lookat, pbrt's
// LookAt and its transform at Camera): a look-at that defines a frame, and a camera-to-world transform
// that is finite and a rotation, translation, uniform scale or mirror (no zero or unequal scale, no shear:
// the camera's rays and pdfs assume an orthonormal frame, common/camera). Each function returns what is
// wrong, or "" when nothing is; the front end reports it at the file and line it read it from.
#pragma once
#include <string>

#include "common/core/transform.h"
#include "common/core/vec.h"

namespace mlt {

// The camera at `origin` looking at `target` with `up` (Transform::lookAt).
std::string lookAtProblem(const Vec3& origin, const Vec3& target, const Vec3& up);
// A camera-to-world transform (an inverse of one, world-to-camera, passes or fails alike).
std::string cameraTransformProblem(const Transform& cameraToWorld);

}  // namespace mlt
