// The light factories a scene is built with: the non-area emitters of SceneDesc::lights and the area
// light of an emitting mesh. The individual constructors are in light_factories.h.
#pragma once
#include <memory>

#include "common/interfaces/light.h"
#include "common/scene/scene_desc.h"

namespace mlt {

// Dispatches on LightDesc::Type; throws std::runtime_error naming the bad field.
std::unique_ptr<Light> makeLight(const LightDesc& desc);
// An area light over every triangle of the mesh (uniform by area), emitting desc.emission on the front.
// With `surface` (the mesh alone as a ray target) and a convex mesh (MeshDesc::convex, faces outward),
// next-event estimation from outside the mesh's bounding sphere samples the cone it subtends instead.
std::unique_ptr<Light> makeAreaLight(const MeshDesc& mesh, std::shared_ptr<const EmitterSurface> surface = nullptr);

}  // namespace mlt
