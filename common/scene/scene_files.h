// Which files a scene may read: the one rule both front ends (Mitsuba XML, pbrt) resolve file names
// with, and the one confinement check the farm's bundles use (common/farm/bundle.h). A farm scene reads
// only files inside its bundle: with a confinement root, absolute names and names that leave the root
// (`..`, symlinks) are refused, so a worker reads nothing its scene hash does not cover.
#pragma once
#include <optional>
#include <string>

#include "common/core/clip.h"

namespace mlt {

// The path of `file` relative to the directory `root` ('/'-separated) when `file` lies inside `root`
// both as written (lexically, after making it absolute) and after following symlinks; nullopt otherwise
// (also for `root` itself).
std::optional<std::string> pathInsideRoot(const std::string& root, const std::string& file);

struct ResolvedFile {
  std::string path;   // absolute, lexically normal; empty on error
  std::string error;  // why not, e.g. "'../x.obj' lies outside the scene's bundle"; no server paths in it
};

// Resolves `name`, referenced by the file `referencingFile`: relative names against that file's folder,
// then against `mainDir` (the main scene file's folder); the first regular file found wins. With a
// non-empty `root`, an absolute name or a candidate outside `root` is an error, and messages name
// paths relative to `root` only.
ResolvedFile resolveSceneFile(const std::string& name, const std::string& referencingFile, const std::string& mainDir,
                              const std::string& root);

}  // namespace mlt
