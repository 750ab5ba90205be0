// Scenes by content hash, as a worker needs them: the bundle's files on disk under `cacheDir/<hash>`
// (fetched once per machine; another worker process may share the directory), and the built render
// scene in memory per (hash, film size, scene parameters), built once by the first task that needs it
// while the others wait. How the files are fetched is the caller's (the worker asks the coordinator).
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/farm/farm_types.h"
#include "common/render/render_scene.h"

namespace mlt::farm {

class SceneCache {
 public:
  // Returns the bundle with this hash; may throw (the error becomes the task's).
  using FetchBundle = std::function<std::vector<BundleFile>(const std::string& sceneHash)>;
  SceneCache(std::string cacheDir, FetchBundle fetch);

  // The render scene of `sceneFile` in the bundle `sceneHash`, loaded with `defines`, for a film of
  // width x height. Thread-safe. The fetched bundle must hash to `sceneHash`, and the scene may read only
  // the bundle's files. Errors: FarmError(InvalidArgument) from the loader or a bundle that does not match
  // its hash, or the fetch's.
  std::shared_ptr<const RenderScene> get(const std::string& sceneHash, const std::string& sceneFile,
                                         const std::map<std::string, std::string>& defines, int width, int height);

 private:
  struct Entry {
    std::mutex mu;
    std::shared_ptr<const RenderScene> scene;
  };
  std::string dir_;
  FetchBundle fetch_;
  std::mutex mu_;
  std::map<std::string, std::shared_ptr<Entry>> entries_;  // key: hash + film size + defines
};

}  // namespace mlt::farm
