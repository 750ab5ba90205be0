// Loading a scene for the farm: the same code on the coordinator (validation, bootstrap) and the worker
// (chains), so both build the identical RenderScene for a job.
#pragma once
#include <map>
#include <memory>
#include <string>

#include "common/methods/registry.h"
#include "common/render/render_scene.h"
#include "common/scene/scene_desc.h"

namespace mlt::farm {

// loadScene (Mitsuba XML or pbrt-v3 by extension); errors become FarmError(InvalidArgument) carrying the loader's message.
// `defines` are the job's scene parameters (Mitsuba -D).
SceneDesc loadSceneDesc(const std::string& path, const std::map<std::string, std::string>& defines = {});
// Fills what the client left to the scene: film size, max depth, rr depth.
void resolveSettings(RenderSettings& s, bool hasSize, bool hasMaxDepth, bool hasRrDepth, bool hasSpp,
                     const SceneDesc& desc);
// Builds the render scene for a film of width x height (the camera's raster follows the job's size).
std::unique_ptr<RenderScene> buildRenderScene(SceneDesc desc, int width, int height);

}  // namespace mlt::farm
