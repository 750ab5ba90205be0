// Crash-safe file replacement (see durable_file.h).
#include "common/core/durable_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <stdexcept>
#include <system_error>

namespace mlt {
namespace {

[[noreturn]] void fail(const std::string& path, const char* what, int err) {
  // A std::system_error (a std::runtime_error) keeps errno, so a caller can tell a full disk from the rest.
  throw std::system_error(err, std::generic_category(), fmt::format("{}: cannot {}", path, what));
}

std::string parentOf(const std::string& path) {
  std::string dir = std::filesystem::path(path).parent_path().string();
  return dir.empty() ? "." : dir;
}

// open(path, O_RDONLY | extraFlags), fsync, close; errors name the step (openWhat / syncWhat).
void openAndSync(const std::string& path, int extraFlags, const char* openWhat, const char* syncWhat) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | extraFlags);
  if (fd < 0) fail(path, openWhat, errno);
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    fail(path, syncWhat, err);
  }
  ::close(fd);
}

void syncFile(const std::string& path) { openAndSync(path, 0, "open for fsync", "fsync"); }

}  // namespace

void syncDirectory(const std::string& dir) {
  openAndSync(dir, O_DIRECTORY, "open the directory for fsync", "fsync the directory");
}

void writeFileDurably(const std::string& path, std::string_view data, mode_t mode) {
  // A name of its own per writer: two threads or processes may write the same path at once.
  static std::atomic<unsigned> serial{0};
  const std::string tmp = fmt::format("{}.tmp-{}-{}", path, ::getpid(), serial++);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0) fail(tmp, "create", errno);
  auto abandon = [&](const char* what, int err) {
    ::close(fd);
    ::unlink(tmp.c_str());
    fail(tmp, what, err);
  };
  if (::fchmod(fd, mode) != 0) abandon("set the permissions of", errno);  // the umask does not apply
  for (size_t done = 0; done < data.size();) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) abandon("write", n < 0 ? errno : EIO);
    done += size_t(n);
  }
  if (::fsync(fd) != 0) abandon("fsync", errno);
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    fail(tmp, "close", err);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    fail(path, "rename the temporary file onto", err);
  }
  syncDirectory(parentOf(path));
}

void commitFileDurably(const std::string& tmpPath, const std::string& path) {
  syncFile(tmpPath);
  if (::rename(tmpPath.c_str(), path.c_str()) != 0) fail(path, "rename the temporary file onto", errno);
  syncDirectory(parentOf(path));
}

}  // namespace mlt
