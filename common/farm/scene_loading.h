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
// `defines` are the job's scene parameters (Mitsuba -D). `root`: the bundle's directory; the scene may
// read only files inside it (common/scene/scene_files.h), and messages name files relative to it (a
// coordinator's or worker's own directories never appear in them).
SceneDesc loadSceneDesc(const std::string& path, const std::map<std::string, std::string>& defines = {},
                        const std::string& root = {});
// `message` with the directory `root` (as given, and absolute) removed from the file names in it: errors
// sent to a client never name the coordinator's own directories.
std::string hideRoot(std::string message, const std::string& root);
// Fills what the client left to the scene: film size, max depth, rr depth.
void resolveSettings(RenderSettings& s, bool hasSize, bool hasMaxDepth, bool hasRrDepth, bool hasSpp,
                     const SceneDesc& desc);
// Builds the render scene for a film of width x height (the camera's raster follows the job's size).
std::unique_ptr<RenderScene> buildRenderScene(SceneDesc desc, int width, int height);

}  // namespace mlt::farm
