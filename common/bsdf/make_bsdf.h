// The BSDF factory: validates a scene's BsdfDesc and builds the concrete BSDF (bsdfs.h).
#pragma once
#include <memory>

#include "common/interfaces/bsdf.h"
#include "common/scene/scene_desc.h"

namespace mlt {

// Builds the BSDF for a description (textures loaded here). Throws std::runtime_error naming desc.id.
std::unique_ptr<Bsdf> makeBsdf(const SceneDesc& scene, const BsdfDesc& desc);

}  // namespace mlt
