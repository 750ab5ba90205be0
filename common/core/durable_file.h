// Files that survive a crash whole: after a kill -9 or a power loss, a path written here holds either
// its previous contents (or nothing) or all of the new bytes, never a torn mix. The recipe: write a
// temporary file in the same directory, fsync it, rename it over the path, fsync the directory (so the
// rename itself is on disk).
#pragma once
#include <sys/types.h>

#include <string>
#include <string_view>

namespace mlt {

// Writes `data` to `path` durably (see above), with permissions `mode` (e.g. 0600 for a secret).
// Throws std::system_error (errno as its code) naming the file and the system's reason.
void writeFileDurably(const std::string& path, std::string_view data, mode_t mode = 0644);

// For a file another library wrote (an EXR, a PNG) at `tmpPath`, in the same directory as `path`:
// fsyncs it, renames it over `path` and fsyncs the directory.
void commitFileDurably(const std::string& tmpPath, const std::string& path);

// fsyncs a directory, making the creations, renames and deletions inside it durable.
void syncDirectory(const std::string& dir);

}  // namespace mlt
