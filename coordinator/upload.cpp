// Accepting a task's result (WorkerHandler::admitUpload, upload): only from the worker holding the task's
// live lease, checked against the task (result_check.h), accepted once per
// (job, task), persisted (result_store.h) before it is acknowledged and summed into the job's running
// total in task order; the last one hands the job to the merge.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <optional>

#include "coordinator/coordinator.h"
#include "coordinator/result_check.h"
#include "coordinator/crash_point.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

using Code = FarmError::Code;

}  // namespace

void Coordinator::requireLease(const Job& job, const std::string& workerId, const std::string& leaseId,
                               uint32_t taskIndex) {
  if (!knownWorker(workerId))
    throw FarmError(Code::FailedPrecondition, fmt::format("worker_id: unknown worker '{}'", workerId.substr(0, 80)));
  std::string why;
  const LeaseRec* l = liveLease(workerId, leaseId, why);
  if (l && (l->job != job.rec.id || l->task != taskIndex))
    why = fmt::format("lease_id: lease {} is for another task", leaseId.substr(0, 80));
  if (!l || !why.empty()) {
    spdlog::warn("job={} task={} worker={} lease={} event=upload_refused reason=\"{}\"", job.status.jobId, taskIndex,
                 workerId.substr(0, 80), leaseId.substr(0, 80), why);
    throw FarmError(Code::FailedPrecondition, why);
  }
}

void Coordinator::admitUpload(const UploadAnnouncement& a) {
  std::lock_guard lock(mu_);
  Job& job = findJob(a.jobId);
  if (!job.plan) throw FarmError(Code::FailedPrecondition, fmt::format("job {} has no plan", a.jobId));
  if (a.taskIndex >= job.tasks.size())
    throw FarmError(Code::InvalidArgument,
                    fmt::format("task_index: {} out of range [0, {})", a.taskIndex, job.tasks.size()));
  // A task already accepted, or a job no longer running, is answered by upload() (accepted = false) once
  // the film is read: the duplicate of a lost reply is no error.
  if (job.status.state == JobState::Running && job.taskState[a.taskIndex] != TaskState::Accepted)
    requireLease(job, a.workerId, a.leaseId, a.taskIndex);
  if (a.width != job.plan->settings.width || a.height != job.plan->settings.height)
    throw FarmError(Code::InvalidArgument, fmt::format("partial.width/height: {}x{}, the job renders {}x{}", a.width,
                                                       a.height, job.plan->settings.width, job.plan->settings.height));
  const uint32_t maxLayer = maxSplatLayer(*job.plan);
  if (!a.splatLayers.empty() && a.splatLayers.back() > maxLayer)
    throw FarmError(Code::InvalidArgument, fmt::format("partial.splat_layers: layer {} (this job fills layers 0-{})",
                                                       a.splatLayers.back(), maxLayer));
}

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
      metrics_.uploadsRefused.Increment();
      return UploadReply{false, fmt::format("job {} is {}", jobId, jobStateName(job.status.state))};
    }
    if (job.taskState[taskIndex] == TaskState::Accepted) {
      spdlog::warn("job={} task={} worker={} lease={} event=duplicate_dropped", jobId, taskIndex, workerId, leaseId);
      metrics_.uploadsRefused.Increment();
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
    if (auto r = refused(job)) return *r;
    requireLease(job, workerId, leaseId, taskIndex);  // only from the worker holding the task's live lease
    id = job.rec.id;
    plan = job.plan;
    identity = {job.status.jobId, job.rec.sceneHash, job.rec.sceneFile};
  }
  // The film must be one the task can make before it is stored or counted (outside the lock: it reads
  // every value). Refused: the worker reports the failure, the task is rendered again.
  try {
    checkTaskResult(*plan, taskIndex, range, result);
  } catch (const FarmError& e) {
    spdlog::warn("job={} task={} worker={} lease={} event=upload_refused reason=\"{}\"", jobId, taskIndex, workerId,
                 leaseId, e.what());
    throw;
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
  // Still running and not accepted meanwhile: counted (the film came from the lease holder and passed the
  // checks, even if its lease expired while it was being stored). A job that failed or was cancelled
  // while the film was being stored does not keep it: a restart would count it (recovery reads the stored
  // results), and the failed job's accepted tasks would change.
  if (auto r = refused(job)) {
    if (job.status.state != JobState::Running && job.taskState[taskIndex] != TaskState::Accepted)
      results_->remove(id, taskIndex);
    return *r;
  }
  job.taskState[taskIndex] = TaskState::Accepted;
  metrics_.tasksAccepted.Increment();
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
