// Scene bundles: the scene file plus every file it references, content-hashed (SHA-256), so a
// coordinator and its workers render exactly the bytes the client had. Paths inside a bundle are
// relative to the scene file's directory.
#pragma once
#include <string>
#include <vector>

#include "common/farm/farm_types.h"

namespace mlt::farm {

struct SceneBundle {
  std::vector<BundleFile> files;  // sorted by path
  std::string sceneFile;          // the scene file's path inside the bundle
};

// Loads the scene (for its list of referenced files) and reads every file. The scene and the files it
// references must lie inside `root` (default: the scene file's directory), which becomes the bundle's
// root: the loader refuses anything else (common/scene/scene_files.h), naming file and line. Throws
// FarmError(InvalidArgument) with the loader's message.
// `defines`: the scene's -D parameters (they may name the referenced files).
SceneBundle collectBundle(const std::string& sceneFile, const std::map<std::string, std::string>& defines = {},
                          const std::string& root = {});
// Hex SHA-256 over the sorted (path, size, bytes) triples: the same value as sceneContentHash
// (common/scene/scene_hash.h) for a scene whose files all lie under its directory.
std::string bundleHash(const std::vector<BundleFile>& files);
// Rejects absolute paths, "..", empty components and backslashes (FarmError InvalidArgument).
void validateBundlePath(const std::string& path);
// Writes the files under `dir` (created). Existing files are overwritten.
void writeBundle(const std::string& dir, const std::vector<BundleFile>& files);
// Reads every regular file under `dir`, sorted by path.
std::vector<BundleFile> readBundle(const std::string& dir);

}  // namespace mlt::farm
