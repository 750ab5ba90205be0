// Accepting a task's result (WorkerHandler::upload): checked against the task, accepted once per
// (job, task), persisted (result_store.h) before it is acknowledged and summed into the job's running
// total in task order; the last one hands the job to the merge.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <optional>

#include "coordinator/coordinator.h"
#include "coordinator/crash_point.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

using Code = FarmError::Code;

}  // namespace

UploadReply Coordinator::upload(const std::string& workerId, const std::string& leaseId, const std::string& jobId,
                                uint32_t taskIndex, PartialResult result) {
  // Checked under the lock, persisted outside it (writing megabytes must not stall heartbeats and leases),
  // accepted under it again: whatever changed meanwhile (a cancel, the same task from another worker)
  // decides then.
  std::shared_ptr<const JobPlan> plan;
  JobIdentity identity;
  int64_t id = 0;
  TaskRange range;
  auto refused = [&](Job& job) -> std::optional<UploadReply> {
    if (job.status.state != JobState::Running) {
      spdlog::info("job={} task={} worker={} event=upload_ignored state={}", jobId, taskIndex, workerId,
                   jobStateName(job.status.state));
      return UploadReply{false, fmt::format("job {} is {}", jobId, jobStateName(job.status.state))};
    }
    if (job.taskState[taskIndex] == TaskState::Accepted) {
      spdlog::warn("job={} task={} worker={} lease={} event=duplicate_dropped", jobId, taskIndex, workerId, leaseId);
      return UploadReply{false, fmt::format("task {} of {} was already accepted", taskIndex, jobId)};
    }
    return std::nullopt;
  };
  {
    std::lock_guard lock(mu_);
    Job& job = findJob(jobId);
    if (!job.plan) throw FarmError(Code::FailedPrecondition, fmt::format("job {} has no plan", jobId));
    if (taskIndex >= job.tasks.size())
      throw FarmError(Code::InvalidArgument,
                      fmt::format("task_index: {} out of range [0, {})", taskIndex, job.tasks.size()));
    range = job.tasks[taskIndex];
    if (result.film.width() != job.plan->settings.width || result.film.height() != job.plan->settings.height)
      throw FarmError(Code::InvalidArgument, fmt::format("partial.width/height: {}x{}, the job renders {}x{}",
                                                         result.film.width(), result.film.height(),
                                                         job.plan->settings.width, job.plan->settings.height));
    std::vector<uint32_t> expect;
    for (uint32_t u = range.begin; u < range.end; ++u) expect.push_back(u);
    if (result.units != expect)
      throw FarmError(Code::InvalidArgument, fmt::format("partial.units: task {} must hold units {}-{}", taskIndex,
                                                         range.begin, range.end - 1));
    if (auto r = refused(job)) return *r;
    id = job.rec.id;
    plan = job.plan;
    identity = {job.status.jobId, job.rec.sceneHash, job.rec.sceneFile};
  }
  crashPoint("upload-received");
  // Persist before acknowledging: nothing accepted is lost.
  results_->put(id, taskIndex, result);
  if (opt_.keepPartials) {
    fs::path dir = fs::path(jobDir(id)) / "partials";
    fs::create_directories(dir);
    std::string path = (dir / fmt::format("task-{:04}.exr", taskIndex)).string();
    writePartialExr(path + ".tmp.exr", identity, *plan, taskIndex, result);
    fs::rename(path + ".tmp.exr", path);
  }
  std::lock_guard lock(mu_);
  Job& job = jobs_.at(id);
  if (auto r = refused(job)) return *r;
  job.taskState[taskIndex] = TaskState::Accepted;
  for (auto it = leases_.begin(); it != leases_.end();)
    it = (it->second.job == job.rec.id && it->second.task == taskIndex) ? leases_.erase(it) : std::next(it);
  std::erase(job.pending, taskIndex);
  const double seconds = result.seconds;
  foldAccepted(job, taskIndex, std::move(result));
  refreshProgress(job);
  spdlog::info("job={} task={} units={}-{} worker={} lease={} event=accepted seconds={:.3f} done={}/{}", jobId,
               taskIndex, range.begin, range.end - 1, workerId, leaseId, seconds, job.status.tasksDone,
               job.status.tasksTotal);
  if (job.status.tasksDone == job.tasks.size()) {
    setState(job, JobState::Merging);
    work_.notify_all();
  } else {
    touch(job);
  }
  crashPoint("upload-recorded");
  return {true, "accepted"};
}

}  // namespace mlt::farm
