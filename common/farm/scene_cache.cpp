// Scenes by content hash (see scene_cache.h).
#include "common/farm/scene_cache.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <filesystem>
#include <fmt/format.h>

#include "common/core/durable_file.h"
#include "common/farm/bundle.h"
#include "common/farm/scene_loading.h"

namespace fs = std::filesystem;

namespace mlt::farm {

SceneCache::SceneCache(std::string cacheDir, FetchBundle fetch) : dir_(std::move(cacheDir)), fetch_(std::move(fetch)) {
  fs::create_directories(dir_);
}

std::shared_ptr<const RenderScene> SceneCache::get(const std::string& sceneHash, const std::string& sceneFile,
                                                   const std::map<std::string, std::string>& defines, int width,
                                                   int height) {
  std::string key = fmt::format("{}@{}x{}", sceneHash, width, height);
  for (const auto& [name, value] : defines) key += fmt::format("|{}={}", name, value);
  std::shared_ptr<Entry> entry;
  {
    std::lock_guard lock(mu_);
    auto& e = entries_[key];
    if (!e) e = std::make_shared<Entry>();
    entry = e;
  }
  std::lock_guard lock(entry->mu);  // one thread fetches and builds; the others wait for it
  if (entry->scene) return entry->scene;
  const fs::path dir = fs::path(dir_) / sceneHash;
  if (!fs::exists(dir)) {
    std::vector<BundleFile> files = fetch_(sceneHash);
    // The scene hash covers every byte this worker will read: a bundle that does not hash to it is refused.
    if (const std::string got = bundleHash(files); got != sceneHash)
      throw FarmError(FarmError::Code::InvalidArgument,
                      fmt::format("scene {}: the fetched bundle hashes to {}", sceneHash.substr(0, 12), got.substr(0, 12)));
    const fs::path tmp = dir.string() + fmt::format(".tmp-{}", getpid());
    fs::remove_all(tmp);
    writeBundle(tmp.string(), files);
    std::error_code ec;
    fs::rename(tmp, dir, ec);  // another worker on this machine may have won: same bytes
    if (ec) fs::remove_all(tmp);
    else syncDirectory(dir.parent_path().string());
    spdlog::info("event=scene_cached scene_hash={} files={}", sceneHash.substr(0, 12), files.size());
  }
  validateBundlePath(sceneFile);
  SceneDesc desc = loadSceneDesc((dir / sceneFile).string(), defines, dir.string());  // the bundle's files only
  entry->scene = buildRenderScene(std::move(desc), width, height);
  return entry->scene;
}

}  // namespace mlt::farm
