// Scenes by content hash (see scene_cache.h).
#include "common/farm/scene_cache.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fmt/format.h>

#include "common/core/durable_file.h"
#include "common/farm/bundle.h"
#include "common/farm/scene_loading.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

bool isBundleHash(const std::string& name) {
  return name.size() == 64 && std::all_of(name.begin(), name.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

uint64_t bytesOnDisk(const fs::path& dir) {
  uint64_t bytes = 0;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec))
    if (it->is_regular_file(ec)) bytes += it->file_size(ec);
  return bytes;
}

// Out of the way first (a rename is atomic: nobody loads from a half-deleted bundle), then deleted.
void deleteBundleDir(const std::string& dir) {
  static std::atomic<int> counter{0};
  const std::string gone = fmt::format("{}.evicted-{}-{}", dir, getpid(), counter++);
  std::error_code ec;
  fs::rename(dir, gone, ec);
  if (ec) return;  // another worker on this directory deleted it already
  fs::remove_all(gone, ec);
}

}  // namespace

uint64_t estimateSceneBytes(const SceneDesc& desc) {
  uint64_t mesh = 0;
  for (const MeshDesc& m : desc.meshes)
    mesh += m.positions.size() * sizeof(Vec3) + m.normals.size() * sizeof(Vec3) + m.uvs.size() * sizeof(Vec2) +
            m.indices.size() * sizeof(uint32_t);
  return 3 * mesh + 4096;
}

SceneCache::SceneCache(std::string cacheDir, FetchBundle fetch, uint64_t maxBytes)
    : dir_(std::move(cacheDir)),
      fetch_(std::move(fetch)),
      cache_("scenes", maxBytes, [](const std::string&, const std::shared_ptr<const Cached>& c) {
        if (!c->bundleDir.empty()) deleteBundleDir(c->bundleDir);
      }) {
  fs::create_directories(dir_);
  adoptBundlesOnDisk();
}

void SceneCache::adoptBundlesOnDisk() {
  std::vector<std::pair<fs::file_time_type, fs::path>> found;
  for (const fs::directory_entry& e : fs::directory_iterator(dir_)) {
    std::error_code ec;
    if (e.is_directory(ec) && isBundleHash(e.path().filename().string()))
      found.emplace_back(e.last_write_time(ec), e.path());
  }
  std::sort(found.begin(), found.end());  // oldest first: the first to go
  for (const auto& [time, path] : found)
    cache_.adopt(bundleKey(path.filename().string()), std::make_shared<const Cached>(Cached{nullptr, path.string()}),
                 bytesOnDisk(path));
}

uint64_t SceneCache::materialize(const std::string& sceneHash) {
  const fs::path dir = fs::path(dir_) / sceneHash;
  if (fs::exists(dir)) return bytesOnDisk(dir);  // another worker on this directory fetched it
  std::vector<BundleFile> files = fetch_(sceneHash);
  // The scene hash covers every byte this worker will read: a bundle that does not hash to it is refused.
  if (const std::string got = bundleHash(files); got != sceneHash)
    throw FarmError(FarmError::Code::InvalidArgument,
                    fmt::format("scene {}: the fetched bundle hashes to {}", sceneHash.substr(0, 12), got.substr(0, 12)));
  const fs::path tmp = dir.string() + fmt::format(".tmp-{}-{}", getpid(), gettid());
  fs::remove_all(tmp);
  writeBundle(tmp.string(), files);
  std::error_code ec;
  fs::rename(tmp, dir, ec);  // another worker on this machine may have won: same bytes
  if (ec) fs::remove_all(tmp);
  else syncDirectory(dir.parent_path().string());
  uint64_t bytes = 0;
  for (const BundleFile& f : files) bytes += f.data.size();
  spdlog::info("event=scene_cached scene_hash={} files={} bytes={}", sceneHash.substr(0, 12), files.size(), bytes);
  return bytes;
}

std::shared_ptr<const RenderScene> SceneCache::get(const std::string& sceneHash, const std::string& sceneFile,
                                                   const std::map<std::string, std::string>& defines, int width,
                                                   int height) {
  std::string key = fmt::format("scene:{}@{}x{}", sceneHash, width, height);
  for (const auto& [name, value] : defines) key += fmt::format("|{}={}", name, value);
  auto cached = cache_.get(key, [&]() -> std::pair<std::shared_ptr<const Cached>, uint64_t> {
    const fs::path dir = fs::path(dir_) / sceneHash;
    // The bundle is in use (kept on disk) while this scene loads from it.
    auto bundle = cache_.get(bundleKey(sceneHash), [&] {
      const uint64_t bytes = materialize(sceneHash);
      return std::pair{std::make_shared<const Cached>(Cached{nullptr, dir.string()}), bytes};
    });
    if (!fs::exists(dir)) materialize(sceneHash);  // counted here, deleted by another worker on this directory
    validateBundlePath(sceneFile);
    SceneDesc desc = loadSceneDesc((dir / sceneFile).string(), defines, dir.string());  // the bundle's files only
    const uint64_t bytes = estimateSceneBytes(desc);
    return {std::make_shared<const Cached>(Cached{buildRenderScene(std::move(desc), width, height), ""}), bytes};
  });
  return std::shared_ptr<const RenderScene>(cached, cached->scene.get());  // keeps the pin
}

}  // namespace mlt::farm
