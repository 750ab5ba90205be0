#include "common/scene/scene_loader.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "common/scene/mitsuba_loader.h"
#include "common/scene/pbrt_loader.h"
#include "common/scene/scene_files.h"

namespace mlt {

bool isPbrtScene(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".pbrt";
}

SceneDesc loadScene(const std::string& path, const std::map<std::string, std::string>& defines,
                    const std::string& root) {
  if (!root.empty() && !pathInsideRoot(root, path))
    throw SceneError(clipForMessage(path), 0, "the scene file lies outside the directory it is confined to");
  if (!isPbrtScene(path)) return loadMitsubaScene(path, defines, root);
  if (!defines.empty())
    throw SceneError(path, 0, "-D " + clipForMessage(defines.begin()->first) + "=...: parameters apply to Mitsuba scenes only");
  return loadPbrtScene(path, root);
}

}  // namespace mlt
