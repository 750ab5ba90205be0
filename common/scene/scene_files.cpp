// Which files a scene may read (see scene_files.h).
#include "common/scene/scene_files.h"

#include <filesystem>
#include <vector>

namespace fs = std::filesystem;

namespace mlt {
namespace {

// `rel` (lexically_relative's result) names something strictly below its base.
bool isBelow(const fs::path& rel) { return !rel.empty() && *rel.begin() != ".." && rel != "."; }

}  // namespace

std::optional<std::string> pathInsideRoot(const std::string& root, const std::string& file) {
  if (root.empty() || file.empty()) return std::nullopt;
  const fs::path r = fs::absolute(root).lexically_normal();
  const fs::path f = fs::absolute(file).lexically_normal();
  const fs::path rel = f.lexically_relative(r);
  if (!isBelow(rel)) return std::nullopt;
  std::error_code ec1, ec2;  // the same after following symlinks (as far as the path exists)
  const fs::path rc = fs::weakly_canonical(r, ec1), fc = fs::weakly_canonical(f, ec2);
  if (ec1 || ec2 || !isBelow(fc.lexically_relative(rc))) return std::nullopt;
  return rel.generic_string();
}

ResolvedFile resolveSceneFile(const std::string& name, const std::string& referencingFile, const std::string& mainDir,
                              const std::string& root) {
  const std::string shown = "'" + clipForMessage(name) + "'";
  if (name.empty()) return {"", "empty file name"};
  if (name.find('\0') != std::string::npos) return {"", shown + " contains a NUL character"};
  const fs::path p(name);
  const bool confined = !root.empty();
  if (confined && p.is_absolute())
    return {"", shown + ": absolute paths are not allowed (a farm scene may reference only files inside its bundle)"};
  std::vector<fs::path> candidates;
  if (p.is_absolute()) {
    candidates.push_back(p);
  } else {
    candidates.push_back(fs::path(referencingFile).parent_path() / p);
    if (fs::path(mainDir) / p != candidates.front()) candidates.push_back(fs::path(mainDir) / p);
  }
  std::string tried;
  for (const fs::path& c : candidates) {
    const std::string abs = fs::absolute(c).lexically_normal().string();
    std::string shownCandidate = c.string();
    if (confined) {
      const std::optional<std::string> rel = pathInsideRoot(root, abs);
      if (!rel) return {"", shown + " lies outside the scene's bundle (a farm scene may reference only files inside it)"};
      shownCandidate = *rel;
    }
    std::error_code ec;
    if (fs::is_regular_file(c, ec)) return {abs, ""};
    tried += (tried.empty() ? "" : ", ") + clipForMessage(shownCandidate);
  }
  return {"", shown + " not found (tried " + tried + ")"};
}

}  // namespace mlt
