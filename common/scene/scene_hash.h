// Content hash of a scene bundle: the scene file plus every file it references, so a worker can fetch
// a scene by hash and a job can prove which inputs produced an image.
#pragma once
#include <string>
#include <vector>

#include "common/scene/scene_desc.h"

namespace mlt {

struct BundleFile {
  std::string relativePath;  // relative to the scene file's folder ('/'-separated); absolute if outside it
  std::string absolutePath;
};

// The scene file and every referenced file, sorted by relativePath (duplicates removed).
std::vector<BundleFile> sceneBundleFiles(const SceneDesc& scene);

// SHA-256 (hex) over, for each bundle file in order: relativePath, '\0', byte count (8 bytes, big
// endian), the bytes. Renaming, moving or editing any input changes the hash; the order in which the
// scene referenced files does not. Throws std::runtime_error if a file cannot be read.
std::string sceneContentHash(const SceneDesc& scene);

}  // namespace mlt
