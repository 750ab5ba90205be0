// The operator's view of the coordinator (see snapshot.h): a copy of every job and worker, and the
// developed image of a job's accepted tasks for the web page.
#include "coordinator/snapshot.h"

#include <spdlog/spdlog.h>

#include <atomic>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>

#include "common/io/png_io.h"
#include "coordinator/coordinator.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

using Code = FarmError::Code;

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FarmError(Code::Internal, fmt::format("{}: cannot read image", path.filename().string()));
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

double unixSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

FarmSnapshot Coordinator::snapshot() {
  std::lock_guard lock(mu_);
  FarmSnapshot out;
  const auto now = Clock::now();
  for (auto& [id, job] : jobs_) {
    refreshProgress(job);
    JobSnapshot j;
    j.status = job.status;
    j.status.elapsedSeconds = unixSeconds() - job.rec.submittedAt;
    j.submittedAt = job.rec.submittedAt;
    j.queuedTasks = uint32_t(job.pending.size());
    j.samplesAccepted = job.samplesAccepted;
    const double rendering = std::chrono::duration<double>(now - job.renderStart).count();
    if (job.status.state == JobState::Running && rendering > 0)
      j.samplesPerSecond = double(job.samplesAccepted - job.samplesAtStart) / rendering;
    j.proposedPerLength = job.statsAccepted.proposedPerLength;
    j.acceptedPerLength = job.statsAccepted.acceptedPerLength;
    out.jobs.push_back(std::move(j));
  }
  std::map<std::string, size_t> index;
  for (const auto& [wid, w] : workers_) {
    index[wid] = out.workers.size();
    out.workers.push_back({wid, w.info.hostname, w.info.threads, w.info.pid,
                           std::chrono::duration<double>(now - w.lastSeen).count(), {}});
  }
  for (const auto& [leaseId, l] : leases_) {
    auto w = index.find(l.workerId);
    auto job = jobs_.find(l.job);
    if (w == index.end() || job == jobs_.end()) continue;
    out.workers[w->second].tasks.push_back({job->second.status.jobId, leaseId, l.task});
  }
  return out;
}

PreviewPng Coordinator::previewPng(const std::string& jobId) {
  std::unique_lock lock(mu_);
  Job& job = findJob(jobId);
  const int64_t id = job.rec.id;
  if (job.status.state == JobState::Done) {
    const uint32_t tasks = job.status.tasksDone;
    lock.unlock();
    return {readAll(fs::path(jobDir(id)) / "image.png"), tasks, true};
  }
  const size_t accepted = job.mergedTasks + job.waiting.size();
  if (job.status.state != JobState::Running || !job.plan || accepted == 0)
    throw FarmError(Code::FailedPrecondition,
                    fmt::format("job {} is {} with no accepted task: no preview yet", jobId, jobStateName(job.status.state)));
  // As writePreview does: the running sum and the tasks beyond it copied under the lock, added in task
  // order outside it, developed exactly as the final image.
  std::shared_ptr<const JobPlan> plan = job.plan;
  PartialResult merged = job.merged;
  std::vector<PartialResult> later;
  for (const auto& [t, r] : job.waiting) later.push_back(r);
  lock.unlock();
  for (const PartialResult& r : later) merged.add(r);
  const std::vector<Color> rgb = developImage(*plan, merged);
  static std::atomic<uint64_t> counter{0};
  const fs::path dir = jobDir(id);
  fs::create_directories(dir);
  const fs::path tmp = dir / fmt::format("web-preview-{}-{}.tmp.png", instance_, counter++);
  PreviewPng out;
  try {
    writePng(tmp.string(), plan->settings.width, plan->settings.height, rgb);
    out = {readAll(tmp), uint32_t(accepted), false};
  } catch (...) {
    fs::remove(tmp);
    throw;
  }
  fs::remove(tmp);
  return out;
}

}  // namespace mlt::farm
