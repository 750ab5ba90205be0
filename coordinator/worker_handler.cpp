// The coordinator's WorkerHandler, lease side (see handler.h): registration, leasing (FIFO within
// priorities, long poll), heartbeats, scene and plan downloads, failures and returned leases. Accepting
// an uploaded result: upload.cpp.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fmt/format.h>
#include <optional>

#include "common/farm/bundle.h"
#include "coordinator/coordinator.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

using Code = FarmError::Code;

}  // namespace

Registration Coordinator::registerWorker(const WorkerInfo& info) {
  std::lock_guard lock(mu_);
  Registration r;
  r.workerId = creds_->workerId(instance_, nextWorker_++);
  r.heartbeatSeconds = opt_.heartbeatSeconds;
  r.leaseTimeoutSeconds = opt_.leaseTimeoutSeconds;
  workers_[r.workerId] = {info, Clock::now()};
  spdlog::info("worker={} event=registered host={} pid={} threads={}", r.workerId, info.hostname, info.pid, info.threads);
  return r;
}

std::vector<Lease> Coordinator::lease(const std::string& workerId, int maxTasks) {
  std::unique_lock lock(mu_);
  WorkerRec* w = knownWorker(workerId);
  if (!w) throw FarmError(Code::FailedPrecondition, fmt::format("worker_id: unknown worker '{}': register again", workerId));
  w->lastSeen = Clock::now();
  // Long poll: with nothing to lease, wait (up to leaseWaitSeconds) for work to appear (a plan finished,
  // a task requeued) instead of letting the worker poll: an idle worker starts within milliseconds.
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(opt_.leaseWaitSeconds));
  std::vector<Lease> out;
  while (!stopping_) {
    out = leaseNow(workerId, maxTasks);
    if (!out.empty() || Clock::now() >= until) break;
    changed_.wait_until(lock, until);
  }
  return out;
}

std::vector<Lease> Coordinator::leaseNow(const std::string& workerId, int maxTasks) {
  // FIFO within priorities: higher priority first, then submission order (= id order).
  std::vector<Job*> running;
  for (auto& [id, job] : jobs_)
    if (job.status.state == JobState::Running && !job.pending.empty()) running.push_back(&job);
  std::stable_sort(running.begin(), running.end(),
                   [](Job* a, Job* b) { return a->status.priority > b->status.priority; });
  std::vector<Lease> out;
  for (Job* job : running) {
    while (int(out.size()) < maxTasks && !job->pending.empty()) {
      uint32_t t = job->pending.front();
      job->pending.pop_front();
      job->taskState[t] = TaskState::Leased;
      Lease l;
      l.leaseId = creds_->leaseId(instance_, nextLease_++, job->rec.id, t, workerId);
      l.jobId = job->status.jobId;
      l.taskIndex = t;
      l.unitBegin = job->tasks[t].begin;
      l.unitEnd = job->tasks[t].end;
      l.sceneHash = job->rec.sceneHash;
      l.sceneFile = job->rec.sceneFile;
      l.defines = job->defines;
      leases_[l.leaseId] = {workerId, job->rec.id, t,
                            Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                               std::chrono::duration<double>(opt_.leaseTimeoutSeconds))};
      metrics_.tasksLeased.Increment();
      spdlog::info("job={} task={} units={}-{} worker={} lease={} event=leased", l.jobId, t, l.unitBegin,
                   l.unitEnd - 1, workerId, l.leaseId);
      out.push_back(std::move(l));
    }
    refreshProgress(*job);
    touch(*job);
    if (int(out.size()) >= maxTasks) break;
  }
  return out;
}

Coordinator::WorkerRec* Coordinator::knownWorker(const std::string& workerId) {
  if (auto w = workers_.find(workerId); w != workers_.end()) return &w->second;
  if (!creds_->validWorker(workerId)) return nullptr;
  spdlog::info("worker={} event=worker_resumed (registered before a restart, or silent for a while)", workerId);
  return &(workers_[workerId] = {WorkerInfo{}, Clock::now()});
}

Coordinator::LeaseRec* Coordinator::liveLease(const std::string& workerId, const std::string& leaseId, std::string& why) {
  if (auto it = leases_.find(leaseId); it != leases_.end()) {
    if (it->second.workerId == workerId) return &it->second;
    why = fmt::format("lease_id: lease {} is held by another worker", leaseId.substr(0, 80));
    return nullptr;
  }
  // Not in the table: it expired, or this process restarted since it was issued. Taken back when its task
  // waits for a worker; lost when it was given away (leased again), accepted, or the job is over.
  const std::optional<LeaseClaim> claim = creds_->parseLease(leaseId, workerId);
  if (!claim) {
    why = fmt::format("lease_id: '{}' is not a lease of worker '{}'", leaseId.substr(0, 80), workerId.substr(0, 80));
    return nullptr;
  }
  auto j = jobs_.find(claim->job);
  if (j == jobs_.end() || j->second.status.state != JobState::Running || claim->task >= j->second.tasks.size()) {
    why = fmt::format("lease_id: lease {} belongs to a job that is not running", leaseId.substr(0, 80));
    return nullptr;
  }
  Job& job = j->second;
  if (job.returnedLeases.count(leaseId)) {
    why = fmt::format("lease_id: lease {} was returned by its worker", leaseId.substr(0, 80));
    return nullptr;
  }
  if (job.taskState[claim->task] != TaskState::Pending) {
    why = fmt::format("lease_id: lease {} of task {} of {} expired and the task was {}", leaseId.substr(0, 80),
                      claim->task, job.status.jobId,
                      job.taskState[claim->task] == TaskState::Accepted ? "accepted from another worker"
                                                                         : "leased to another worker");
    return nullptr;
  }
  std::erase(job.pending, claim->task);
  job.taskState[claim->task] = TaskState::Leased;
  LeaseRec& l = leases_[leaseId] = {workerId, job.rec.id, claim->task,
                                    Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                       std::chrono::duration<double>(opt_.leaseTimeoutSeconds))};
  spdlog::info("job={} task={} worker={} lease={} event=lease_resumed", job.status.jobId, claim->task, workerId, leaseId);
  refreshProgress(job);
  touch(job);
  return &l;
}

HeartbeatReply Coordinator::heartbeat(const std::string& workerId, const std::vector<std::string>& leaseIds) {
  std::lock_guard lock(mu_);
  HeartbeatReply r;
  WorkerRec* w = knownWorker(workerId);
  if (!w) {
    r.unknownWorker = true;
    return r;
  }
  w->lastSeen = Clock::now();
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(opt_.leaseTimeoutSeconds));
  for (const std::string& id : leaseIds) {
    // A lease the worker no longer holds (given away after it expired, its task accepted, its job over,
    // or never its own) is named in the reply: the worker abandons that task.
    std::string why;
    LeaseRec* l = liveLease(workerId, id, why);
    auto job = l ? jobs_.find(l->job) : jobs_.end();
    if (!l || job == jobs_.end() || job->second.status.state != JobState::Running ||
        job->second.taskState[l->task] == TaskState::Accepted) {
      r.cancelledLeases.push_back(id);
      if (l) leases_.erase(id);
      else spdlog::info("worker={} lease={} event=lease_lost reason=\"{}\"", workerId, id.substr(0, 80), why);
      continue;
    }
    l->deadline = deadline;
  }
  return r;
}

std::vector<BundleFile> Coordinator::scene(const std::string& sceneHash) {
  if (sceneHash.size() != 64 || !std::all_of(sceneHash.begin(), sceneHash.end(), [](char c) {
        return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
      }))
    throw FarmError(Code::InvalidArgument, fmt::format("scene_hash: '{}' is not a SHA-256 hex digest", sceneHash));
  const std::string dir = sceneDir(sceneHash);
  if (!fs::is_directory(dir)) throw FarmError(Code::NotFound, fmt::format("scene_hash: unknown scene {}", sceneHash));
  return readBundle(dir);
}

JobPlan Coordinator::plan(const std::string& jobId) { return *sharedPlan(jobId); }

std::shared_ptr<const JobPlan> Coordinator::sharedPlan(const std::string& jobId) {
  std::lock_guard lock(mu_);
  Job& job = findJob(jobId);
  if (!job.plan) throw FarmError(Code::FailedPrecondition, fmt::format("job {} has no plan yet", jobId));
  return job.plan;
}

bool Coordinator::taskAttemptFailed(Job& job, uint32_t task, const std::string& reason) {
  // Only a task that is still leased counts: a late report for a task that has meanwhile been accepted,
  // requeued or re-leased elsewhere says nothing about the current attempt.
  job.taskState[task] = TaskState::Pending;
  const uint32_t n = ++job.attempts[task];
  ++job.status.failedAttempts;
  metrics_.taskFailures.Increment();
  const TaskRange r = job.tasks[task];
  if (job.status.state != JobState::Running) {
    touch(job);
    return false;
  }
  if (int(n) >= opt_.maxAttempts) {
    spdlog::error("job={} task={} units={}-{} event=task_out_of_attempts attempts={} error=\"{}\"", job.status.jobId, task,
                  r.begin, r.end - 1, n, reason);
    setState(job, JobState::Failed,
             fmt::format("task {} (work units {}-{}) failed {} times; last error: {}", task, r.begin, r.end - 1, n, reason));
    return true;
  }
  job.pending.push_front(task);
  metrics_.tasksRequeued.Increment();
  spdlog::warn("job={} task={} units={}-{} event=requeued attempt={}/{} error=\"{}\"", job.status.jobId, task, r.begin,
               r.end - 1, n, opt_.maxAttempts, reason);
  touch(job);
  return false;
}

FailureReply Coordinator::reportFailure(const std::string& workerId, const std::string& leaseId,
                                        const std::string& jobId, uint32_t taskIndex, const std::string& message) {
  std::lock_guard lock(mu_);
  Job& job = findJob(jobId);
  if (taskIndex >= job.tasks.size())
    throw FarmError(Code::InvalidArgument,
                    fmt::format("task_index: {} out of range [0, {})", taskIndex, job.tasks.size()));
  auto it = leases_.find(leaseId);
  if (it == leases_.end() || it->second.workerId != workerId || it->second.job != job.rec.id ||
      it->second.task != taskIndex) {
    spdlog::info("job={} task={} worker={} lease={} event=stale_failure_ignored error=\"{}\"", jobId, taskIndex,
                 workerId, leaseId, message);
    return {};
  }
  leases_.erase(it);
  if (job.taskState[taskIndex] != TaskState::Leased) return {};
  spdlog::warn("job={} task={} worker={} lease={} event=task_failed error=\"{}\"", jobId, taskIndex, workerId, leaseId,
               message);
  return {taskAttemptFailed(job, taskIndex, fmt::format("worker {}: {}", workerId, message))};
}

void Coordinator::returnLeases(const std::string& workerId, const std::vector<std::string>& leaseIds) {
  std::lock_guard lock(mu_);
  for (const std::string& id : leaseIds) {
    auto it = leases_.find(id);
    if (it == leases_.end() || it->second.workerId != workerId) continue;
    auto job = jobs_.find(it->second.job);
    if (job != jobs_.end()) job->second.returnedLeases.insert(id);
    if (job != jobs_.end() && job->second.taskState[it->second.task] == TaskState::Leased) {
      job->second.taskState[it->second.task] = TaskState::Pending;
      if (job->second.status.state == JobState::Running) {
        job->second.pending.push_front(it->second.task);
        metrics_.tasksRequeued.Increment();
      }
      spdlog::info("job={} task={} worker={} lease={} event=returned", job->second.status.jobId, it->second.task,
                   workerId, id);
      touch(job->second);
    }
    leases_.erase(it);
  }
}

}  // namespace mlt::farm
