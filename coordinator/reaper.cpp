// The reaper thread: a lease not renewed by heartbeats within the lease timeout counts as a failed
// attempt (requeued, or the job fails when the task is out of attempts); workers silent for three
// timeouts are forgotten.
#include <spdlog/spdlog.h>

#include <fmt/format.h>

#include "coordinator/coordinator.h"

namespace mlt::farm {

void Coordinator::reaperLoop() {
  std::unique_lock lock(mu_);
  while (!stopping_) {
    changed_.wait_for(lock, std::chrono::milliseconds(200));
    try {
      const auto now = Clock::now();
      for (auto it = leases_.begin(); it != leases_.end();) {
        if (it->second.deadline > now) {
          ++it;
          continue;
        }
        auto job = jobs_.find(it->second.job);
        if (job != jobs_.end() && job->second.taskState[it->second.task] == TaskState::Leased) {
          metrics_.leasesExpired.Increment();
          spdlog::warn("job={} task={} worker={} lease={} event=lease_expired", job->second.status.jobId,
                       it->second.task, it->second.workerId, it->first);
          taskAttemptFailed(job->second, it->second.task,
                            fmt::format("lease {} of worker {} expired (worker died or hung)", it->first,
                                        it->second.workerId));
        }
        it = leases_.erase(it);
      }
      const auto forget = std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>(3 * opt_.leaseTimeoutSeconds));
      for (auto it = workers_.begin(); it != workers_.end();)
        it = (now - it->second.lastSeen > forget) ? workers_.erase(it) : std::next(it);
    } catch (const std::exception& e) {  // never ends the process; the next round tries again
      spdlog::error("event=reaper_error error=\"{}\"", e.what());
    }
  }
}

}  // namespace mlt::farm
