// Reference images for the evaluation: rendered by the project (a long run of a trusted method, bdpt by
// default, as K independent parts with different seeds so that its own noise can be estimated, see
// metrics.h) and cached, or supplied by the user as an EXR (noise unknown, reported as such).
//
// Cache: DIR/refs/<key>.exr (the reference, with its noise level in the header) and <key>.var.exr (the
// per-pixel variance of the reference). key = FNV-1a over the scene content hash and every setting that
// changes the reference (method, spp, parts, seed, size, max depth, rr depth).
#pragma once
#include <string>
#include <vector>

#include "common/methods/registry.h"
#include "tools/eval/metrics.h"
#include "tools/eval/run_record.h"

namespace mlt::eval {

struct ReferenceSettings {
  std::string method = "bdpt";
  int spp = 1024;      // total over all parts
  int parts = 4;       // K >= 2
  uint64_t seed = 0x7ef5eed;
};

struct Reference {
  int width = 0, height = 0;
  std::vector<Color> image;
  std::vector<Color> variance;  // empty when unknown
  ReferenceInfo info;
};

// Renders (or loads from cacheDir, when both cacheDir and sceneHash are non-empty) the reference.
// base: the runs' settings (size, depth); method, spp, seed are replaced by the reference's.
Reference obtainReference(const RenderScene& scene, const RenderSettings& base, const ReferenceSettings& settings,
                          const std::string& sceneName, const std::string& sceneHash, const std::string& cacheDir,
                          double eps, int threads);

// A user-supplied EXR; its size must be width x height (std::runtime_error naming the file otherwise).
Reference loadUserReference(const std::string& path, const std::string& sceneName, int width, int height);

std::string referenceCacheKey(const std::string& sceneHash, const RenderSettings& base,
                              const ReferenceSettings& settings);

}  // namespace mlt::eval
