#include "common/scene/scene_hash.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "common/core/sha256.h"
#include "common/scene/scene_files.h"

namespace fs = std::filesystem;

namespace mlt {

std::vector<BundleFile> sceneBundleFiles(const SceneDesc& scene) {
  const fs::path main = fs::absolute(scene.sourceFile).lexically_normal();
  const fs::path dir = main.parent_path();
  std::vector<BundleFile> files;
  auto add = [&](const std::string& p) {
    const fs::path abs = fs::absolute(p).lexically_normal();
    const std::optional<std::string> rel = pathInsideRoot(dir.string(), abs.string());
    files.push_back({rel ? *rel : abs.generic_string(), abs.string()});
  };
  add(scene.sourceFile);
  for (const std::string& f : scene.referencedFiles) add(f);
  std::sort(files.begin(), files.end(), [](const BundleFile& a, const BundleFile& b) { return a.relativePath < b.relativePath; });
  files.erase(std::unique(files.begin(), files.end(),
                          [](const BundleFile& a, const BundleFile& b) { return a.relativePath == b.relativePath; }),
              files.end());
  return files;
}

std::string sceneContentHash(const SceneDesc& scene) {
  Sha256 h;
  std::vector<char> buf(1 << 16);
  for (const BundleFile& f : sceneBundleFiles(scene)) {
    std::ifstream in(f.absolutePath, std::ios::binary);
    if (!in) throw std::runtime_error(f.absolutePath + ": cannot open scene file for hashing");
    std::error_code ec;
    const uint64_t size = fs::file_size(f.absolutePath, ec);
    if (ec) throw std::runtime_error(f.absolutePath + ": cannot stat scene file for hashing");
    h.update(f.relativePath);
    const uint8_t zero = 0;
    h.update(&zero, 1);
    uint8_t len[8];
    for (int i = 0; i < 8; ++i) len[i] = uint8_t(size >> (56 - 8 * i));
    h.update(len, 8);
    uint64_t read = 0;
    while (in) {
      in.read(buf.data(), std::streamsize(buf.size()));
      h.update(buf.data(), size_t(in.gcount()));
      read += uint64_t(in.gcount());
    }
    if (in.bad() || read != size) throw std::runtime_error(f.absolutePath + ": changed or unreadable while hashing");
  }
  return h.hexDigest();
}

}  // namespace mlt
