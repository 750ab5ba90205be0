// Scene bundles (see bundle.h).
#include "common/farm/bundle.h"

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>

#include "common/core/durable_file.h"
#include "common/core/sha256.h"
#include "common/scene/scene_loader.h"
#include "common/core/clip.h"
#include "common/scene/scene_files.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw FarmError(FarmError::Code::InvalidArgument, fmt::format("{}: cannot read file", p.string()));
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

void validateBundlePath(const std::string& path) {
  auto bad = [&](const char* why) {
    throw FarmError(FarmError::Code::InvalidArgument, fmt::format("bundle path '{}': {}", clipForMessage(path), why));
  };
  if (path.empty()) bad("empty");
  if (path.front() == '/') bad("absolute paths are not allowed");
  if (path.find('\\') != std::string::npos) bad("backslashes are not allowed");
  // A NUL ends the name the file system sees (the file written would not be the file hashed).
  if (std::any_of(path.begin(), path.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20; }))
    bad("control characters (NUL, newline, ...) are not allowed");
  size_t start = 0;
  while (start <= path.size()) {
    size_t end = path.find('/', start);
    if (end == std::string::npos) end = path.size();
    std::string part = path.substr(start, end - start);
    if (part.empty() || part == "." || part == "..") bad("empty, '.' or '..' component");
    start = end + 1;
  }
}

SceneBundle collectBundle(const std::string& sceneFile, const std::map<std::string, std::string>& defines,
                          const std::string& rootDir) {
  const fs::path scenePath = fs::absolute(sceneFile).lexically_normal();
  const std::string root = rootDir.empty() ? scenePath.parent_path().string() : rootDir;
  SceneDesc desc;
  try {
    desc = loadScene(scenePath.string(), defines, root);  // the client's own paths: named in full
  } catch (const std::exception& e) {
    throw FarmError(FarmError::Code::InvalidArgument, e.what());
  }
  std::vector<std::string> paths{scenePath.string()};
  paths.insert(paths.end(), desc.referencedFiles.begin(), desc.referencedFiles.end());
  SceneBundle bundle;
  for (const std::string& p : paths) {
    const std::optional<std::string> rel = pathInsideRoot(root, p);  // the loader checked; the bundle relies on it
    if (!rel)
      throw FarmError(FarmError::Code::InvalidArgument,
                      fmt::format("{}: referenced file {} lies outside {}", sceneFile, p, root));
    if (p == paths.front()) bundle.sceneFile = *rel;
    if (std::any_of(bundle.files.begin(), bundle.files.end(), [&](const BundleFile& f) { return f.path == *rel; }))
      continue;
    bundle.files.push_back({*rel, readFile(p)});
  }
  std::sort(bundle.files.begin(), bundle.files.end(), [](auto& a, auto& b) { return a.path < b.path; });
  return bundle;
}

std::string bundleHash(const std::vector<BundleFile>& files) {
  std::vector<const BundleFile*> sorted;
  for (const auto& f : files) sorted.push_back(&f);
  std::sort(sorted.begin(), sorted.end(), [](auto* a, auto* b) { return a->path < b->path; });
  Sha256 sha;  // common/core: the same digest as sceneContentHash, with no crypto library below the farm
  for (const BundleFile* f : sorted) {
    // Same scheme as common/scene/scene_hash.h: path, '\0', 8-byte big-endian size, bytes.
    std::string head = f->path + '\0';
    for (int b = 7; b >= 0; --b) head += char((uint64_t(f->data.size()) >> (8 * b)) & 0xff);
    sha.update(head);
    sha.update(f->data);
  }
  return sha.hexDigest();
}

void writeBundle(const std::string& dir, const std::vector<BundleFile>& files) {
  for (const BundleFile& f : files) {
    validateBundlePath(f.path);
    fs::path p = fs::path(dir) / f.path;
    fs::create_directories(p.parent_path());
    try {
      writeFileDurably(p.string(), f.data);
    } catch (const std::exception& e) {
      throw FarmError(FarmError::Code::Internal, e.what());
    }
  }
  // The subdirectories' entries too: after a crash the bundle is whole once its directory is renamed in.
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_directory()) syncDirectory(e.path().string());
  syncDirectory(dir);
}

std::vector<BundleFile> readBundle(const std::string& dir) {
  std::vector<BundleFile> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    files.push_back({entry.path().lexically_relative(dir).generic_string(), readFile(entry.path())});
  }
  std::sort(files.begin(), files.end(), [](auto& a, auto& b) { return a.path < b.path; });
  return files;
}

}  // namespace mlt::farm
