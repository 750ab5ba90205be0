// State-directory failures as statuses (see storage_error.h).
#include "coordinator/storage_error.h"

#include <cerrno>
#include <cstring>
#include <fmt/format.h>

namespace mlt::farm {

FarmError storageError(const std::string& what, int err) {
  if (err == 0) err = EIO;
  const bool full = err == ENOSPC || err == EDQUOT || err == EFBIG;
  // what() of a std::filesystem error already carries the reason; a plain message gets strerror.
  const std::string reason = what.find(std::strerror(err)) != std::string::npos ? what
                                                                                 : fmt::format("{}: {}", what, std::strerror(err));
  return FarmError(full ? FarmError::Code::ResourceExhausted : FarmError::Code::Unavailable,
                   fmt::format("coordinator storage: {}", reason));
}

void throwStorageError(const std::string& what) { throw storageError(what, errno); }

}  // namespace mlt::farm
