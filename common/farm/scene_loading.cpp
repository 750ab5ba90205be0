// Scene loading shared by coordinator and worker (see scene_loading.h).
#include "common/farm/scene_loading.h"

#include <filesystem>

#include "common/farm/farm_types.h"
#include "common/scene/scene_loader.h"

namespace mlt::farm {

std::string hideRoot(std::string message, const std::string& root) {
  if (root.empty()) return message;
  for (std::string prefix : {root, std::filesystem::absolute(root).lexically_normal().string()}) {
    if (prefix.empty()) continue;
    if (prefix.back() != '/') prefix += '/';
    if (prefix == "/" || prefix == "./") continue;
    for (size_t at = message.find(prefix); at != std::string::npos; at = message.find(prefix, at))
      message.erase(at, prefix.size());
  }
  return message;
}

SceneDesc loadSceneDesc(const std::string& path, const std::map<std::string, std::string>& defines,
                        const std::string& root) {
  try {
    return loadScene(path, defines, root);
  } catch (const std::exception& e) {
    throw FarmError(FarmError::Code::InvalidArgument, root.empty() ? e.what() : hideRoot(e.what(), root));
  }
}

void resolveSettings(RenderSettings& s, bool hasSize, bool hasMaxDepth, bool hasRrDepth, bool hasSpp,
                     const SceneDesc& desc) {
  if (desc.sampleCount && takesSceneSampleCount(s, hasSpp)) s.spp = *desc.sampleCount;
  if (!hasSize) {
    s.width = desc.camera.width;
    s.height = desc.camera.height;
  }
  if (!hasMaxDepth && desc.maxDepth) s.integrator.maxDepth = *desc.maxDepth;
  if (!hasRrDepth && desc.rrDepth) s.integrator.rrDepth = *desc.rrDepth;
  if (s.width <= 0 || s.height <= 0)
    throw FarmError(FarmError::Code::InvalidArgument,
                    "settings.width/height: the film is " + std::to_string(s.width) + "x" + std::to_string(s.height));
}

std::unique_ptr<RenderScene> buildRenderScene(SceneDesc desc, int width, int height) {
  desc.camera.width = width;
  desc.camera.height = height;
  try {
    return RenderScene::build(desc);
  } catch (const std::exception& e) {
    throw FarmError(FarmError::Code::InvalidArgument, desc.sourceFile + ": " + e.what());
  }
}

}  // namespace mlt::farm
