// Self-checking worker and lease ids (see credentials.h).
#include "coordinator/credentials.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <charconv>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <random>
#include <sstream>

#include "common/core/sha256.h"
#include "coordinator/storage_error.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

constexpr size_t kKeyBytes = 32;
constexpr size_t kMacHex = 32;

std::string hex(const uint8_t* p, size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (size_t i = 0; i < n; ++i) {
    out += digits[p[i] >> 4];
    out += digits[p[i] & 15];
  }
  return out;
}

// Constant time in the length of `a`: the check does not tell an attacker how many digits were right.
bool sameText(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

bool parseUnsigned(const std::string& s, uint64_t& v) {
  if (s.empty() || s.size() > 19) return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size();
}

std::string readKey(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

Credentials::Credentials(const std::string& stateDir) {
  const std::string path = (fs::path(stateDir) / "lease.key").string();
  key_ = readKey(path);
  if (key_.size() == kKeyBytes) return;
  if (!key_.empty()) throw FarmError(FarmError::Code::Internal, fmt::format("{}: not a {}-byte key", path, kKeyBytes));
  std::random_device rd;
  std::string key(kKeyBytes, '\0');
  for (char& c : key) c = char(rd() & 0xff);
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  if (fd < 0) throwStorageError(fmt::format("{}: cannot create", tmp));
  const bool written = ::write(fd, key.data(), key.size()) == ssize_t(key.size()) && ::fsync(fd) == 0;
  const int err = errno;
  ::close(fd);
  if (!written) throw storageError(fmt::format("{}: cannot write", tmp), err);
  fs::rename(tmp, path);
  key_ = key;
}

std::string Credentials::mac(const std::string& message) const {
  // HMAC (RFC 2104): H((K ^ opad) || H((K ^ ipad) || m)), the key padded to the 64-byte block.
  std::array<uint8_t, 64> ipad{}, opad{};
  for (size_t i = 0; i < 64; ++i) {
    const uint8_t k = i < key_.size() ? uint8_t(key_[i]) : 0;
    ipad[i] = k ^ 0x36;
    opad[i] = k ^ 0x5c;
  }
  Sha256 inner;
  inner.update(ipad.data(), ipad.size());
  inner.update(message);
  const std::array<uint8_t, 32> h = inner.digest();
  Sha256 outer;
  outer.update(opad.data(), opad.size());
  outer.update(h.data(), h.size());
  const std::array<uint8_t, 32> d = outer.digest();
  return hex(d.data(), kMacHex / 2);
}

std::string Credentials::workerId(const std::string& instance, uint64_t n) const {
  const std::string body = fmt::format("w{}-{}", instance, n);
  return body + "." + mac("worker|" + body);
}

bool Credentials::validWorker(const std::string& workerId) const {
  const size_t dot = workerId.rfind('.');
  if (dot == std::string::npos || workerId.size() > 128) return false;
  return sameText(workerId.substr(dot + 1), mac("worker|" + workerId.substr(0, dot)));
}

std::string Credentials::leaseId(const std::string& instance, uint64_t n, int64_t job, uint32_t task,
                                 const std::string& workerId) const {
  const std::string body = fmt::format("l{}-{}.{}.{}", instance, n, job, task);
  return body + "." + mac("lease|" + body + "|" + workerId);
}

std::optional<LeaseClaim> Credentials::parseLease(const std::string& leaseId, const std::string& workerId) const {
  if (leaseId.size() > 128 || workerId.size() > 128) return std::nullopt;
  const size_t macDot = leaseId.rfind('.');
  if (macDot == std::string::npos) return std::nullopt;
  const std::string body = leaseId.substr(0, macDot);
  if (!sameText(leaseId.substr(macDot + 1), mac("lease|" + body + "|" + workerId))) return std::nullopt;
  const size_t taskDot = body.rfind('.');
  const size_t jobDot = taskDot == std::string::npos || taskDot == 0 ? std::string::npos : body.rfind('.', taskDot - 1);
  uint64_t job = 0, task = 0;
  if (jobDot == std::string::npos || !parseUnsigned(body.substr(jobDot + 1, taskDot - jobDot - 1), job) ||
      !parseUnsigned(body.substr(taskDot + 1), task) || task > UINT32_MAX || job > uint64_t(INT64_MAX))
    return std::nullopt;
  return LeaseClaim{int64_t(job), uint32_t(task)};
}

}  // namespace mlt::farm
