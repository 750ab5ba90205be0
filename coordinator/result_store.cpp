// Accepted task results as files (see result_store.h).
#include "coordinator/result_store.h"


#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>

#include "common/core/durable_file.h"
#include "coordinator/storage_error.h"
#include "proto/convert.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

constexpr char kMagic[8] = {'M', 'L', 'T', 'R', 'E', 'S', '0', '1'};

// Word-wise multiplicative hash of the bytes: detects a torn or zero-filled file, at memory speed.
uint64_t checksum(const char* p, size_t n) {
  uint64_t h = 0x6a09e667f3bcc908ull ^ n;
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = ((h << 5) | (h >> 59)) ^ w;
    h *= 0x9e3779b97f4a7c15ull;
  }
  for (; i < n; ++i) h = (h ^ uint8_t(p[i])) * 0x100000001b3ull;
  return h ^ (h >> 31);
}

std::string jobName(int64_t job) { return fmt::format("job-{}", job); }

}  // namespace

ResultStore::ResultStore(std::string jobsDir) : dir_(std::move(jobsDir)) {}

std::string ResultStore::path(int64_t job, uint32_t task) const {
  return (fs::path(dir_) / jobName(job) / "results" / fmt::format("task-{:06}.part", task)).string();
}

void ResultStore::put(int64_t job, uint32_t task, const PartialResult& result) const {
  const std::string blob = wire::serializePartial(result, /*zeroRuns=*/true);
  const uint64_t sum = checksum(blob.data(), blob.size());
  const std::string final = path(job, task);
  fs::create_directories(fs::path(final).parent_path());
  // Durable before the upload is acknowledged: temporary file, fsync, rename, fsync the directory. A full
  // disk answers RESOURCE_EXHAUSTED, any other refusal UNAVAILABLE (storage_error.h).
  std::string bytes;
  bytes.reserve(sizeof kMagic + blob.size() + sizeof sum);
  bytes.append(kMagic, sizeof kMagic).append(blob).append(reinterpret_cast<const char*>(&sum), sizeof sum);
  try {
    writeFileDurably(final, bytes);
  } catch (const std::system_error& e) {
    throw storageError(fmt::format("cannot store the result of task {}: {}", task, e.what()), e.code().value());
  }
}

void ResultStore::remove(int64_t job, uint32_t task) const {
  std::error_code ec;
  fs::remove(path(job, task), ec);
}

std::vector<uint32_t> ResultStore::stored(int64_t job) const {
  std::vector<uint32_t> tasks;
  const fs::path dir = fs::path(dir_) / jobName(job) / "results";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    unsigned task = 0;
    char tail = 0;
    if (name.size() == 16 && std::sscanf(name.c_str(), "task-%6u.par%c", &task, &tail) == 2 && tail == 't')
      tasks.push_back(task);
  }
  std::sort(tasks.begin(), tasks.end());
  return tasks;
}

std::optional<PartialResult> ResultStore::load(int64_t job, uint32_t task, std::string* why) const {
  auto fail = [&](const std::string& reason) -> std::optional<PartialResult> {
    if (why) *why = reason;
    return std::nullopt;
  };
  std::ifstream in(path(job, task), std::ios::binary);
  if (!in) return fail("missing");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string bytes = ss.str();
  if (bytes.size() < 16 || std::memcmp(bytes.data(), kMagic, 8) != 0) return fail("not a result file");
  uint64_t sum;
  std::memcpy(&sum, bytes.data() + bytes.size() - 8, 8);
  const std::string blob = bytes.substr(8, bytes.size() - 16);
  if (checksum(blob.data(), blob.size()) != sum) return fail("checksum mismatch (torn write)");
  try {
    return wire::parsePartial(blob);
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}

}  // namespace mlt::farm
