// Loads a scene file by its extension: `.pbrt` -> the pbrt-v3 front end (pbrt_loader.h), anything else ->
// the Mitsuba XML front end (mitsuba_loader.h). Both produce the same SceneDesc.
#pragma once
#include <map>
#include <string>

#include "common/scene/scene_desc.h"
#include "common/scene/scene_error.h"

namespace mlt {

bool isPbrtScene(const std::string& path);

// `defines` are Mitsuba's -D name=value parameters; a pbrt scene has none (a non-empty map is an error).
// `root`: when non-empty, the scene file and every file it reads must lie inside this directory
// (common/scene/scene_files.h): a farm scene reads only its bundle. Otherwise a SceneError naming the
// file, line and the offending name.
SceneDesc loadScene(const std::string& path, const std::map<std::string, std::string>& defines = {},
                    const std::string& root = {});

}  // namespace mlt
