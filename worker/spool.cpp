// Finished films spooled on disk while the coordinator is away (see spool.h).
#include "worker/spool.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>

#include "common/core/sha256.h"
#include "proto/convert.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

constexpr char kMagic[8] = {'M', 'L', 'T', 'S', 'P', 'L', '0', '1'};

void putU64(std::string& out, uint64_t v) { out.append(reinterpret_cast<const char*>(&v), 8); }
void putText(std::string& out, const std::string& s) {
  putU64(out, s.size());
  out += s;
}

struct Reader {
  const std::string& in;
  size_t at = 0;
  bool ok = true;
  uint64_t u64() {
    uint64_t v = 0;
    if (at + 8 > in.size()) return ok = false, 0;
    std::memcpy(&v, in.data() + at, 8);
    at += 8;
    return v;
  }
  std::string text(uint64_t max) {
    const uint64_t n = u64();
    if (!ok || n > max || at + n > in.size()) return ok = false, std::string();
    std::string s = in.substr(at, n);
    at += n;
    return s;
  }
};

std::string digest(const char* p, size_t n) {
  Sha256 h;
  h.update(p, n);
  const auto d = h.digest();
  return std::string(reinterpret_cast<const char*>(d.data()), 8);
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The spooled bytes: magic, target, the serialized partial, 8 bytes of its SHA-256.
std::string encode(const UploadTarget& t, const PartialResult& r) {
  std::string out(kMagic, sizeof kMagic);
  putText(out, t.workerId);
  putText(out, t.leaseId);
  putText(out, t.jobId);
  putU64(out, t.taskIndex);
  putText(out, wire::serializePartial(r, /*zeroRuns=*/true));
  out += digest(out.data(), out.size());
  return out;
}

// nullopt if torn or not a spooled film; `result` is filled only when asked for.
std::optional<UploadTarget> decode(const std::string& bytes, PartialResult* result) {
  if (bytes.size() < sizeof kMagic + 8 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) return std::nullopt;
  if (digest(bytes.data(), bytes.size() - 8) != bytes.substr(bytes.size() - 8)) return std::nullopt;
  Reader r{bytes, sizeof kMagic};
  UploadTarget t;
  t.workerId = r.text(4096);
  t.leaseId = r.text(4096);
  t.jobId = r.text(4096);
  const uint64_t task = r.u64();
  const std::string blob = r.text(bytes.size());
  if (!r.ok || task > UINT32_MAX) return std::nullopt;
  t.taskIndex = uint32_t(task);
  if (result) {
    try {
      *result = wire::parsePartial(blob);
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }
  return t;
}

}  // namespace

FilmSpool::FilmSpool(std::string dir, uint64_t maxBytes) : dir_(std::move(dir)), maxBytes_(maxBytes) {
  fs::create_directories(dir_);
  // Films of a worker process that is gone (SIGKILL, a crash, a stop while the coordinator was away):
  // renamed to this process's name (atomic: one worker takes each) and uploaded like its own.
  std::vector<fs::path> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir_, ec)) found.push_back(e.path());
  std::sort(found.begin(), found.end());
  for (const fs::path& p : found) {
    const std::string name = p.filename().string();
    long pid = 0;
    unsigned long long n = 0;
    char tail[8] = {};
    const bool film = std::sscanf(name.c_str(), "%ld-%llu.fil%1s", &pid, &n, tail) == 3 &&
                      std::strcmp(tail, "m") == 0 && name.find(".tmp") == std::string::npos;
    if (!film) {
      if (name.find(".tmp") != std::string::npos && (pid <= 0 || pid == getpid() || ::kill(pid_t(pid), 0) != 0))
        fs::remove(p, ec);  // a write cut short
      continue;
    }
    std::string mine = p.string();
    if (pid == getpid()) {  // left by an earlier process with this pid: this one has written nothing yet
      next_ = std::max<uint64_t>(next_, n + 1);
    } else {
      if (pid > 0 && (::kill(pid_t(pid), 0) == 0 || errno != ESRCH)) continue;  // its worker still runs
      // Renamed to this process's name: atomic, so one worker takes each; never over an existing film.
      int rc = -1;
      for (int tries = 0; tries < 1000 && rc != 0; ++tries) {
        mine = (fs::path(dir_) / fmt::format("{}-{}.film", getpid(), next_++)).string();
        rc = ::renameat2(AT_FDCWD, p.c_str(), AT_FDCWD, mine.c_str(), RENAME_NOREPLACE);
        if (rc != 0 && errno != EEXIST) break;  // another worker took it
      }
      if (rc != 0) continue;
    }
    if (auto e = adopt(mine)) {
      spdlog::info("event=spool_adopted file={} job={} task={}", name, e->target.jobId, e->target.taskIndex);
      bytes_ += e->bytes;
      entries_.push_back(std::move(*e));
    }
  }
}

std::optional<FilmSpool::Entry> FilmSpool::adopt(const std::string& path) {
  const std::string bytes = readAll(path);
  std::optional<UploadTarget> t = decode(bytes, nullptr);
  if (!t) {
    spdlog::warn("event=spool_dropped file={} reason=\"torn or not a spooled film\"", path);
    std::error_code ec;
    fs::remove(path, ec);
    return std::nullopt;
  }
  return Entry{path, *t, bytes.size()};
}

bool FilmSpool::put(const UploadTarget& target, const PartialResult& result) {
  const std::string bytes = encode(target, result);
  std::string path;
  {
    std::lock_guard lock(mu_);
    if (bytes_ + bytes.size() > maxBytes_) {
      spdlog::warn("job={} task={} event=spool_full film_bytes={} spooled_bytes={} limit={}", target.jobId,
                   target.taskIndex, bytes.size(), bytes_, maxBytes_);
      return false;
    }
    bytes_ += bytes.size();  // reserved while it is written
    path = (fs::path(dir_) / fmt::format("{}-{}.film", getpid(), next_++)).string();
  }
  const std::string tmp = path + ".tmp";
  bool ok = false;
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    ok = bool(out.flush());
  }
  std::error_code ec;
  if (ok) fs::rename(tmp, path, ec);
  std::lock_guard lock(mu_);
  if (!ok || ec) {
    fs::remove(tmp, ec);
    bytes_ -= bytes.size();
    spdlog::warn("job={} task={} event=spool_write_failed file={}", target.jobId, target.taskIndex, tmp);
    return false;
  }
  entries_.push_back({path, target, bytes.size()});
  spdlog::info("job={} task={} lease={} event=spooled bytes={} spooled={}", target.jobId, target.taskIndex,
               target.leaseId, bytes.size(), entries_.size());
  return true;
}

size_t FilmSpool::size() const {
  std::lock_guard lock(mu_);
  return entries_.size();
}

uint64_t FilmSpool::bytes() const {
  std::lock_guard lock(mu_);
  return bytes_;
}

std::vector<std::string> FilmSpool::leaseIds(const std::string& workerId) const {
  std::lock_guard lock(mu_);
  std::vector<std::string> ids;
  for (const Entry& e : entries_)
    if (e.target.workerId == workerId) ids.push_back(e.target.leaseId);
  return ids;
}

void FilmSpool::remove(const Entry& e) {
  std::error_code ec;
  fs::remove(e.path, ec);
  std::lock_guard lock(mu_);
  for (auto it = entries_.begin(); it != entries_.end(); ++it)
    if (it->path == e.path) {
      bytes_ -= it->bytes;
      entries_.erase(it);
      break;
    }
}

size_t FilmSpool::drain(const std::function<Outcome(const UploadTarget&, const PartialResult&)>& upload) {
  std::lock_guard drainLock(drainMu_);
  size_t removed = 0;
  while (true) {
    Entry e;
    {
      std::lock_guard lock(mu_);
      if (entries_.empty()) return removed;
      e = entries_.front();
    }
    PartialResult result;
    const std::optional<UploadTarget> t = decode(readAll(e.path), &result);
    if (t && upload(*t, result) == Outcome::Retry) return removed;
    if (!t) spdlog::warn("event=spool_dropped file={} reason=\"torn or unreadable\"", e.path);
    remove(e);
    ++removed;
  }
}

}  // namespace mlt::farm
