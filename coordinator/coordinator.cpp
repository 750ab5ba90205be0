// The coordinator's shared state (see coordinator.h): construction, the job table and the helpers every
// role uses (state changes, progress). The roles live beside it, one file each: client_handler.cpp,
// worker_handler.cpp (leases), upload.cpp (accepting results), planner.cpp (bootstrap), merge_job.cpp,
// reaper.cpp (lease expiry), preview.cpp, recovery.cpp (reload after a restart).
#include "coordinator/coordinator.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fmt/format.h>
#include <optional>
#include <random>

#include "common/core/clip.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

using Code = FarmError::Code;

std::string phaseText(JobState s, uint32_t tasksDone, uint32_t tasksTotal) {
  switch (s) {
    case JobState::Queued: return "queued";
    case JobState::Planning: return "bootstrap";
    case JobState::Running: return fmt::format("rendering {}/{} tasks", tasksDone, tasksTotal);
    case JobState::Merging: return "merging";
    case JobState::Done: return "done";
    case JobState::Failed: return "failed";
    case JobState::Cancelled: return "cancelled";
  }
  return "?";
}

}  // namespace

std::string formatJobId(int64_t id) { return fmt::format("job-{}", id); }

int64_t parseJobId(const std::string& jobId) {
  if (jobId.rfind("job-", 0) == 0 && jobId.size() > 4 && jobId.size() < 20 &&
      std::all_of(jobId.begin() + 4, jobId.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return std::stoll(jobId.substr(4));
  throw FarmError(Code::NotFound, fmt::format("job_id: unknown job '{}'", clipForMessage(jobId, 32)));
}

Coordinator::Coordinator(CoordinatorOptions options) : opt_(std::move(options)) {
  fs::create_directories(fs::path(opt_.stateDir) / "scenes");
  fs::create_directories(fs::path(opt_.stateDir) / "jobs");
  store_ = std::make_unique<JobStore>((fs::path(opt_.stateDir) / "farm.db").string());
  results_ = std::make_unique<ResultStore>((fs::path(opt_.stateDir) / "jobs").string());
  creds_ = std::make_unique<Credentials>(opt_.stateDir);
  std::random_device rd;
  instance_ = fmt::format("{:08x}", uint32_t(rd()));

  recover();  // coordinator/recovery.cpp
  planner_ = std::thread([this] { plannerLoop(); });
  reaper_ = std::thread([this] { reaperLoop(); });
  if (opt_.previewEverySeconds > 0) preview_ = std::thread([this] { previewLoop(); });
}

Coordinator::~Coordinator() { stop(); }

void Coordinator::stop() {
  {
    std::lock_guard lock(mu_);
    if (stopping_) return;
    stopping_ = true;
  }
  work_.notify_all();
  changed_.notify_all();
  if (planner_.joinable()) planner_.join();
  if (reaper_.joinable()) reaper_.join();
  if (preview_.joinable()) preview_.join();
}

std::string Coordinator::sceneDir(const std::string& hash) const {
  return (fs::path(opt_.stateDir) / "scenes" / hash).string();
}
std::string Coordinator::jobDir(int64_t id) const {
  return (fs::path(opt_.stateDir) / "jobs" / formatJobId(id)).string();
}

Coordinator::Job& Coordinator::findJob(const std::string& jobId) {
  auto it = jobs_.find(parseJobId(jobId));
  if (it == jobs_.end() || it->second.deleted) throw FarmError(Code::NotFound, fmt::format("job_id: unknown job '{}'", jobId));
  return it->second;
}

void Coordinator::touch(Job& job) {
  ++job.status.version;
  changed_.notify_all();
}

void Coordinator::setState(Job& job, JobState s, const std::string& error) {
  job.status.state = s;
  if (!error.empty()) job.status.error = error;
  if (isTerminal(s)) {
    job.pending.clear();  // stop leasing; leases in flight are cancelled by heartbeats
    job.merged = {};      // the running sum is done with (the image is written, or there will be none)
    job.waiting.clear();
  }
  try {
    store_->updateState(job.rec.id, int(s), job.status.error);
  } catch (const std::exception& e) {  // the state stays in memory; a restart finds the last recorded one
    spdlog::error("job={} event=state_not_recorded state={} error=\"{}\"", job.status.jobId, jobStateName(s), e.what());
  }
  refreshProgress(job);
  touch(job);
  spdlog::info("job={} event=state state={}{}", job.status.jobId, jobStateName(s),
               error.empty() ? "" : fmt::format(" error=\"{}\"", error));
}

void Coordinator::runGuarded(int64_t id, const char* role, const std::function<void()>& step) {
  std::string error;
  try {
    step();
    return;
  } catch (const std::exception& e) {
    error = e.what();
  } catch (...) {
    error = "unknown exception";
  }
  std::lock_guard lock(mu_);
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return;
  spdlog::error("job={} event={}_failed error=\"{}\"", it->second.status.jobId, role, error);
  if (!isTerminal(it->second.status.state)) setState(it->second, JobState::Failed, fmt::format("{}: {}", role, error));
}

void Coordinator::startRunning(Job& job, bool loadResults) {
  job.tasks = splitTasks(*job.plan);
  job.taskState.assign(job.tasks.size(), TaskState::Pending);
  job.attempts.assign(job.tasks.size(), 0);
  job.merged = emptyPartial(*job.plan);
  job.mergedTasks = 0;
  job.waiting.clear();
  job.samplesAccepted = 0;
  job.statsAccepted = {};
  for (uint32_t t : results_->stored(job.rec.id)) {
    if (t >= job.taskState.size()) continue;
    if (!loadResults) {  // a finished job: its image is written, only the count is shown
      job.taskState[t] = TaskState::Accepted;
      continue;
    }
    std::string why;
    std::optional<PartialResult> r = results_->load(job.rec.id, t, &why);
    if (!r) {
      spdlog::warn("job={} task={} event=stored_result_dropped reason=\"{}\"", job.status.jobId, t, why);
      continue;  // rendered again
    }
    job.taskState[t] = TaskState::Accepted;
    foldAccepted(job, t, std::move(*r));
  }
  if (!loadResults) job.merged = {};
  job.pending.clear();
  for (uint32_t t = 0; t < job.tasks.size(); ++t)
    if (job.taskState[t] == TaskState::Pending) job.pending.push_back(t);
  job.renderStart = Clock::now();
  refreshProgress(job);
  job.workDoneAtStart = job.status.workDone;
  job.samplesAtStart = job.samplesAccepted;
  job.status.b = job.plan->norm.b;
  job.status.bStdErr = job.plan->norm.bStdErr;
  job.status.bootstrapSeconds = job.plan->norm.bootstrapSeconds;
}

void Coordinator::foldAccepted(Job& job, uint32_t task, PartialResult result) {
  job.samplesAccepted += result.samples;
  job.statsAccepted.add(result.stats);
  job.waiting.emplace(task, std::move(result));
  // Task order, whatever the arrival order: the sum's bits never depend on which worker was faster.
  for (auto it = job.waiting.begin(); it != job.waiting.end() && it->first == job.mergedTasks;
       it = job.waiting.erase(it), ++job.mergedTasks)
    job.merged.add(it->second);
}

void Coordinator::refreshProgress(Job& job) {
  JobStatus& st = job.status;
  st.tasksTotal = uint32_t(job.tasks.size());
  st.tasksDone = st.leasedTasks = 0;
  st.workDone = st.workTotal = 0;
  st.unitsDone = 0;
  st.unitsTotal = job.plan ? uint32_t(job.plan->units.size()) : 0;
  for (size_t t = 0; t < job.tasks.size(); ++t) {
    uint64_t w = 0;
    for (uint32_t u = job.tasks[t].begin; u < job.tasks[t].end; ++u) w += unitWork(*job.plan, job.plan->units[u]);
    st.workTotal += w;
    if (job.taskState[t] == TaskState::Accepted) {
      ++st.tasksDone;
      st.workDone += w;
      st.unitsDone += job.tasks[t].end - job.tasks[t].begin;
    } else if (job.taskState[t] == TaskState::Leased) {
      ++st.leasedTasks;
    }
  }
  st.etaSeconds = -1;
  if (st.state == JobState::Running && st.workDone > job.workDoneAtStart) {
    double elapsed = std::chrono::duration<double>(Clock::now() - job.renderStart).count();
    st.etaSeconds = elapsed * double(st.workTotal - st.workDone) / double(st.workDone - job.workDoneAtStart);
  }
  if (st.state == JobState::Done) st.etaSeconds = 0;
  st.phase = phaseText(st.state, st.tasksDone, st.tasksTotal);
}

}  // namespace mlt::farm
