// Mitsuba XML scene front end (0.6 and 3.x spellings) -> SceneDesc. See scenes/README.md for the
// supported subset. Everything outside the subset that would change the image is a SceneError naming
// the file, the line and the construct; parameters without effect on our renderer are accepted from an
// explicit allow-list; approximations (e.g. a gaussian rfilter rendered as box) are listed in
// SceneDesc::warnings.
#pragma once
#include <map>
#include <string>

#include "common/scene/scene_desc.h"
#include "common/scene/scene_error.h"

namespace mlt {

// `defines` are Mitsuba's command-line -D name=value parameters; they override <default> values and
// are substituted for $name in every attribute.
// `root`: when non-empty, the scene may read only files inside this directory (scene_files.h).
SceneDesc loadMitsubaScene(const std::string& path, const std::map<std::string, std::string>& defines = {},
                           const std::string& root = {});

}  // namespace mlt
