// Scenes by content hash, as a worker needs them: the bundle's files on disk under `cacheDir/<hash>`
// (fetched once per machine; another worker process may share the directory), and the built render
// scene in memory per (hash, film size, scene parameters), built once by the first task that needs it
// while the others wait. How the files are fetched is the caller's (the worker asks the coordinator).
//
// Bounded (common/farm/lru_map.h): bundles on disk (their bytes) and built scenes in memory (an estimate:
// their meshes, three times over for the description, the ray tracer's copy and its BVH) count against one
// bound; past it, the least recently used entries that no task holds go: an evicted bundle's directory is
// deleted, an evicted scene is freed, and the next task that needs either fetches or builds it again. A
// scene returned by get() is in use while the pointer (or a copy) lives. Bundles left in the directory by
// an earlier worker are counted at start (oldest first). Worker processes sharing one directory each
// count it on their own; a bundle another one deleted is fetched again.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/farm/farm_types.h"
#include "common/farm/lru_map.h"
#include "common/render/render_scene.h"

namespace mlt::farm {

// An estimate of the memory a built scene takes (see above).
uint64_t estimateSceneBytes(const SceneDesc& desc);

class SceneCache {
 public:
  static constexpr uint64_t kDefaultMaxBytes = 2048ull << 20;
  // Returns the bundle with this hash; may throw (the error becomes the task's).
  using FetchBundle = std::function<std::vector<BundleFile>(const std::string& sceneHash)>;
  // maxBytes > 0 (std::invalid_argument otherwise).
  SceneCache(std::string cacheDir, FetchBundle fetch, uint64_t maxBytes = kDefaultMaxBytes);

  // The render scene of `sceneFile` in the bundle `sceneHash`, loaded with `defines`, for a film of
  // width x height; in use (never evicted) while the returned pointer lives. Thread-safe. The fetched
  // bundle must hash to `sceneHash`, and the scene may read only the bundle's files. Errors:
  // FarmError(InvalidArgument) from the loader or a bundle that does not match its hash, or the fetch's.
  std::shared_ptr<const RenderScene> get(const std::string& sceneHash, const std::string& sceneFile,
                                         const std::map<std::string, std::string>& defines, int width, int height);

  uint64_t bytes() const { return cache_.bytes(); }  // what counts against the bound now
  bool hasBundle(const std::string& sceneHash) const { return cache_.contains(bundleKey(sceneHash)); }

 private:
  struct Cached {  // one of the two
    std::shared_ptr<const RenderScene> scene;
    std::string bundleDir;
  };
  static std::string bundleKey(const std::string& hash) { return "bundle:" + hash; }
  // Fetches the bundle into its directory unless it is there already; returns its bytes on disk.
  uint64_t materialize(const std::string& sceneHash);
  void adoptBundlesOnDisk();

  std::string dir_;
  FetchBundle fetch_;
  LruMap<Cached> cache_;  // keys "bundle:<hash>" and "scene:<hash>@WxH|defines"
};

}  // namespace mlt::farm
