// The camera factory: perspective (pinhole) and thin-lens cameras from a scene's CameraDesc.
#pragma once
#include <memory>

#include "common/interfaces/camera.h"
#include "common/scene/scene_desc.h"

namespace mlt {

// Throws std::runtime_error naming the bad field (film size, fov, near clip, transform, aperture).
std::unique_ptr<Camera> makeCamera(const CameraDesc& desc);

}  // namespace mlt
