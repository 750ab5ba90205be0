// Failures of the coordinator's state directory (SQLite database, bundles, result files, images) as the
// status a caller can act on: a full disk is RESOURCE_EXHAUSTED (free space and retry), anything else the
// directory refuses (read-only, I/O error, permissions) is UNAVAILABLE. Never a reason to end the process:
// a request answers with it, a background step fails its job with it.
#pragma once
#include <string>

#include "common/farm/farm_types.h"

namespace mlt::farm {

// `what` names the file; `err` is the errno value (0: unknown, treated as an I/O error).
FarmError storageError(const std::string& what, int err);

// Throws storageError(what, errno) with errno as set by the failed call (EIO if it is 0).
[[noreturn]] void throwStorageError(const std::string& what);

}  // namespace mlt::farm
