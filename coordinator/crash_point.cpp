// Test-only crash points (see crash_point.h).
#include "coordinator/crash_point.h"

#include <signal.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <cstring>
#include <fmt/format.h>
#include <stdexcept>

namespace mlt::farm {
namespace {

constexpr const char* kPoints[] = {"upload-received", "upload-recorded", "final-merge"};

std::atomic<const char*> gArmed{nullptr};  // one of kPoints, or null
std::atomic<long> gRemaining{0};

}  // namespace

void armCrashPoint(const std::string& spec) {
  const size_t colon = spec.find(':');
  const std::string name = spec.substr(0, colon);
  long count = 1;
  if (colon != std::string::npos) {
    try {
      size_t used = 0;
      count = std::stol(spec.substr(colon + 1), &used);
      if (used != spec.size() - colon - 1) throw std::invalid_argument("trailing characters");
    } catch (const std::exception&) {
      throw std::invalid_argument(fmt::format("--debug-crash-at {}: the count after ':' is not a number", spec));
    }
    if (count < 1) throw std::invalid_argument(fmt::format("--debug-crash-at {}: the count must be at least 1", spec));
  }
  for (const char* p : kPoints)
    if (name == p) {
      gRemaining = count;
      gArmed = p;
      spdlog::warn("event=crash_point_armed point={} at={}", p, count);
      return;
    }
  throw std::invalid_argument(fmt::format(
      "--debug-crash-at {}: unknown point (upload-received, upload-recorded, final-merge)", spec));
}

void crashPoint(const char* name) {
  const char* armed = gArmed.load(std::memory_order_relaxed);
  if (!armed || std::strcmp(armed, name) != 0) return;
  if (gRemaining.fetch_sub(1) != 1) return;
  spdlog::warn("event=crash_point point={}", name);
  spdlog::default_logger()->flush();
  ::raise(SIGKILL);
}

}  // namespace mlt::farm
