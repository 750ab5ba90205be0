// The coordinator's state machine (see coordinator.h).
#include "coordinator/coordinator.h"

#include "common/job/mlt_job.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fmt/format.h>
#include <optional>
#include <random>

#include "coordinator/bundle.h"
#include "coordinator/scene_loading.h"
#include "proto/convert.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

using Code = FarmError::Code;

double unixNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

constexpr double kMaxTotalWork = 1e12;  // mutations or pixel samples per job

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

const char* jobStateName(JobState s) {
  switch (s) {
    case JobState::Queued: return "QUEUED";
    case JobState::Planning: return "PLANNING";
    case JobState::Running: return "RUNNING";
    case JobState::Merging: return "MERGING";
    case JobState::Done: return "DONE";
    case JobState::Failed: return "FAILED";
    case JobState::Cancelled: return "CANCELLED";
  }
  return "?";
}

std::string formatJobId(int64_t id) { return fmt::format("job-{}", id); }

int64_t parseJobId(const std::string& jobId) {
  if (jobId.rfind("job-", 0) == 0 && jobId.size() > 4 && jobId.size() < 20 &&
      std::all_of(jobId.begin() + 4, jobId.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return std::stoll(jobId.substr(4));
  throw FarmError(Code::NotFound, fmt::format("job_id: unknown job '{}'", jobId));
}

uint64_t Coordinator::unitWork(const JobPlan& plan, const WorkUnit& u) {
  return findMethod(plan.settings.method).unitWork(plan, u);
}

// ---------------------------------------------------------------------------------------------
// Start-up: reload every job from the state directory
// ---------------------------------------------------------------------------------------------
Coordinator::Coordinator(CoordinatorOptions options) : opt_(std::move(options)) {
  fs::create_directories(fs::path(opt_.stateDir) / "scenes");
  fs::create_directories(fs::path(opt_.stateDir) / "jobs");
  store_ = std::make_unique<JobStore>((fs::path(opt_.stateDir) / "farm.db").string());
  std::random_device rd;
  instance_ = fmt::format("{:08x}", uint32_t(rd()));

  for (JobRecord& rec : store_->loadJobs()) {
    Job job;
    job.status.jobId = formatJobId(rec.id);
    job.status.name = rec.name;
    job.status.priority = rec.priority;
    job.status.sceneHash = rec.sceneHash;
    job.status.error = rec.error;
    JobState state = JobState(rec.state);
    try {
      v1::RenderSettings ps;
      ps.ParseFromString(rec.settings);
      wire::SubmittedSettings sub = wire::fromProto(ps);
      RenderSettings s = sub.settings;
      job.defines = sub.defines;
      job.status.method = s.method;
      job.status.width = s.width;
      job.status.height = s.height;
      if (!rec.plan.empty()) job.plan = std::make_shared<JobPlan>(wire::parseJobPlan(rec.plan));
    } catch (const std::exception& e) {
      spdlog::error("job={} event=reload_failed error=\"{}\"", job.status.jobId, e.what());
      state = JobState::Failed;
      job.status.error = std::string("state directory: ") + e.what();
    }
    job.rec = std::move(rec);
    int64_t id = job.rec.id;
    auto& j = jobs_.emplace(id, std::move(job)).first->second;
    if (state == JobState::Planning || (state == JobState::Queued) || (!isTerminal(state) && !j.plan)) {
      state = JobState::Queued;
    }
    j.status.state = state;
    if (j.plan && (state == JobState::Running || state == JobState::Merging || state == JobState::Done)) {
      startRunning(j);
      if (state != JobState::Done) j.status.state = j.status.tasksDone == j.tasks.size() ? JobState::Merging : JobState::Running;
    } else if (j.plan && isTerminal(state)) {
      startRunning(j);  // failed or cancelled: show what was accepted (it is kept), lease nothing
      j.pending.clear();
    }
    refreshProgress(j);
    spdlog::info("job={} event=reloaded state={} tasks_done={}/{}", j.status.jobId, jobStateName(j.status.state),
                 j.status.tasksDone, j.status.tasksTotal);
  }
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
  if (it == jobs_.end()) throw FarmError(Code::NotFound, fmt::format("job_id: unknown job '{}'", jobId));
  return it->second;
}

void Coordinator::touch(Job& job) {
  ++job.status.version;
  changed_.notify_all();
}

void Coordinator::setState(Job& job, JobState s, const std::string& error) {
  job.status.state = s;
  if (!error.empty()) job.status.error = error;
  if (isTerminal(s)) job.pending.clear();  // stop leasing; leases in flight are cancelled by heartbeats
  store_->updateState(job.rec.id, int(s), job.status.error);
  refreshProgress(job);
  touch(job);
  spdlog::info("job={} event=state state={}{}", job.status.jobId, jobStateName(s),
               error.empty() ? "" : fmt::format(" error=\"{}\"", error));
}

void Coordinator::startRunning(Job& job) {
  job.tasks = splitTasks(*job.plan);
  job.taskState.assign(job.tasks.size(), TaskState::Pending);
  job.attempts.assign(job.tasks.size(), 0);
  for (uint32_t t : store_->acceptedTasks(job.rec.id))
    if (t < job.taskState.size()) job.taskState[t] = TaskState::Accepted;
  job.pending.clear();
  for (uint32_t t = 0; t < job.tasks.size(); ++t)
    if (job.taskState[t] == TaskState::Pending) job.pending.push_back(t);
  job.renderStart = Clock::now();
  refreshProgress(job);
  job.workDoneAtStart = job.status.workDone;
  job.status.b = job.plan->norm.b;
  job.status.bStdErr = job.plan->norm.bStdErr;
  job.status.bootstrapSeconds = job.plan->norm.bootstrapSeconds;
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

// ---------------------------------------------------------------------------------------------
// Client side
// ---------------------------------------------------------------------------------------------
JobStatus Coordinator::submit(SubmitRequest req) {
  // 1. The bundle: uploaded files, or collected from a path this process can read.
  SceneBundle bundle;
  if (!req.coordinatorPath.empty()) {
    bundle = collectBundle(req.coordinatorPath, req.defines);
  } else {
    if (req.bundle.empty()) throw FarmError(Code::InvalidArgument, "bundle: no scene files uploaded and no coordinator_path");
    for (const BundleFile& f : req.bundle) validateBundlePath(f.path);
    validateBundlePath(req.bundleSceneFile);
    if (std::none_of(req.bundle.begin(), req.bundle.end(), [&](auto& f) { return f.path == req.bundleSceneFile; }))
      throw FarmError(Code::InvalidArgument,
                      fmt::format("bundle_scene_file: '{}' is not in the uploaded bundle", req.bundleSceneFile));
    bundle.files = std::move(req.bundle);
    bundle.sceneFile = req.bundleSceneFile;
  }
  const std::string hash = bundleHash(bundle.files);
  if (!req.bundleHash.empty() && req.bundleHash != hash)
    throw FarmError(Code::InvalidArgument,
                    fmt::format("bundle_hash: client says {}, the uploaded files hash to {}", req.bundleHash, hash));
  const std::string dir = sceneDir(hash);
  if (!fs::exists(dir)) {
    std::string tmp = dir + ".tmp-" + instance_ + fmt::format("-{}", std::hash<std::thread::id>()(std::this_thread::get_id()));
    fs::remove_all(tmp);
    writeBundle(tmp, bundle.files);
    std::error_code ec;
    fs::rename(tmp, dir, ec);  // another submit of the same bundle may have won: same bytes
    if (ec) fs::remove_all(tmp);
  }
  // 2. Load and validate the scene exactly as the workers will.
  SceneDesc desc = loadSceneDesc((fs::path(dir) / bundle.sceneFile).string(), req.defines);
  RenderSettings s = req.settings;
  resolveSettings(s, req.hasSize, req.hasMaxDepth, req.hasRrDepth, req.hasSpp, desc);
  const double pixels = double(s.width) * s.height;
  if (isMarkovChainMethod(s.method) && s.mutationsPerPixel * pixels > kMaxTotalWork)
    throw FarmError(Code::InvalidArgument,
                    fmt::format("settings.mutations_per_pixel: {} x {} pixels = {:.3g} mutations exceeds the limit {:.0e}",
                                s.mutationsPerPixel, pixels, s.mutationsPerPixel * pixels, kMaxTotalWork));
  if (!isMarkovChainMethod(s.method) && double(s.spp) * pixels > kMaxTotalWork)
    throw FarmError(Code::InvalidArgument, fmt::format("settings.spp: {} x {} pixels exceeds the limit {:.0e}", s.spp,
                                                       pixels, kMaxTotalWork));
  try {
    findMethod(s.method).validate(s);  // e.g. mmlt with the scene's unlimited depth: refused now, not at planning
  } catch (const std::invalid_argument& e) {
    throw FarmError(Code::InvalidArgument, e.what());
  }
  buildRenderScene(desc, s.width, s.height);  // throws InvalidArgument naming the element

  // 3. Record it.
  std::lock_guard lock(mu_);
  JobRecord rec;
  rec.name = req.name;
  rec.priority = req.priority;
  rec.state = int(JobState::Queued);
  rec.settings = wire::toProto(wire::SubmittedSettings{s, true, true, true, true, req.defines}).SerializeAsString();
  rec.sceneHash = hash;
  rec.sceneFile = bundle.sceneFile;
  rec.submittedAt = unixNow();
  rec.id = store_->insertJob(rec);
  Job job;
  job.rec = rec;
  job.status.jobId = formatJobId(rec.id);
  job.status.name = rec.name;
  job.status.priority = rec.priority;
  job.status.method = s.method;
  job.status.sceneHash = hash;
  job.status.width = s.width;
  job.status.height = s.height;
  job.defines = req.defines;
  Job& j = jobs_.emplace(rec.id, std::move(job)).first->second;
  refreshProgress(j);
  spdlog::info("job={} event=submitted scene_hash={} scene={} method={} size={}x{} seed={} priority={}", j.status.jobId,
               hash.substr(0, 12), bundle.sceneFile, j.status.method, s.width, s.height, s.seed, rec.priority);
  touch(j);
  work_.notify_all();
  JobStatus out = j.status;
  out.elapsedSeconds = 0;
  return out;
}

JobStatus Coordinator::get(const std::string& jobId) {
  std::lock_guard lock(mu_);
  Job& job = findJob(jobId);
  refreshProgress(job);
  JobStatus out = job.status;
  out.elapsedSeconds = unixNow() - job.rec.submittedAt;
  return out;
}

JobStatus Coordinator::waitForChange(const std::string& jobId, uint64_t afterVersion, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mu_);
  Job* job = &findJob(jobId);
  changed_.wait_for(lock, timeout, [&] { return stopping_ || job->status.version > afterVersion; });
  refreshProgress(*job);
  JobStatus out = job->status;
  out.elapsedSeconds = unixNow() - job->rec.submittedAt;
  return out;
}

JobStatus Coordinator::cancel(const std::string& jobId) {
  std::lock_guard lock(mu_);
  Job& job = findJob(jobId);
  if (isTerminal(job.status.state))
    throw FarmError(Code::FailedPrecondition,
                    fmt::format("job {} is already {}", jobId, jobStateName(job.status.state)));
  job.pending.clear();
  setState(job, JobState::Cancelled);
  return job.status;
}

std::vector<JobStatus> Coordinator::list() {
  std::lock_guard lock(mu_);
  std::vector<JobStatus> out;
  for (auto& [id, job] : jobs_) {
    refreshProgress(job);
    out.push_back(job.status);
    out.back().elapsedSeconds = unixNow() - job.rec.submittedAt;
  }
  return out;
}

std::string Coordinator::resultPath(const std::string& jobId, const std::string& format) {
  std::lock_guard lock(mu_);
  Job& job = findJob(jobId);
  if (format != "exr" && format != "png")
    throw FarmError(Code::InvalidArgument, fmt::format("format: '{}' (exr|png)", format));
  if (job.status.state != JobState::Done)
    throw FarmError(Code::FailedPrecondition,
                    fmt::format("job {} is {}: no result{}", jobId, jobStateName(job.status.state),
                                job.status.error.empty() ? "" : " (" + job.status.error + ")"));
  return (fs::path(jobDir(job.rec.id)) / ("image." + format)).string();
}

// ---------------------------------------------------------------------------------------------
// Worker side
// ---------------------------------------------------------------------------------------------
Registration Coordinator::registerWorker(const WorkerInfo& info) {
  std::lock_guard lock(mu_);
  Registration r;
  r.workerId = fmt::format("w{}-{}", instance_, nextWorker_++);
  r.heartbeatSeconds = opt_.heartbeatSeconds;
  r.leaseTimeoutSeconds = opt_.leaseTimeoutSeconds;
  workers_[r.workerId] = {info, Clock::now()};
  spdlog::info("worker={} event=registered host={} pid={} threads={}", r.workerId, info.hostname, info.pid, info.threads);
  return r;
}

std::vector<Lease> Coordinator::lease(const std::string& workerId, int maxTasks) {
  std::unique_lock lock(mu_);
  auto w = workers_.find(workerId);
  if (w == workers_.end())
    throw FarmError(Code::FailedPrecondition, fmt::format("worker_id: unknown worker '{}': register again", workerId));
  w->second.lastSeen = Clock::now();
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
      l.leaseId = fmt::format("l{}-{}", instance_, nextLease_++);
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

HeartbeatReply Coordinator::heartbeat(const std::string& workerId, const std::vector<std::string>& leaseIds) {
  std::lock_guard lock(mu_);
  HeartbeatReply r;
  auto w = workers_.find(workerId);
  if (w == workers_.end()) {
    r.unknownWorker = true;
    return r;
  }
  w->second.lastSeen = Clock::now();
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(opt_.leaseTimeoutSeconds));
  for (const std::string& id : leaseIds) {
    auto it = leases_.find(id);
    if (it == leases_.end()) continue;  // expired or from before a restart: the upload decides
    auto job = jobs_.find(it->second.job);
    if (job == jobs_.end() || job->second.status.state != JobState::Running ||
        job->second.taskState[it->second.task] == TaskState::Accepted) {
      r.cancelledLeases.push_back(id);
      leases_.erase(it);
      continue;
    }
    it->second.deadline = deadline;
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

JobPlan Coordinator::plan(const std::string& jobId) {
  std::lock_guard lock(mu_);
  Job& job = findJob(jobId);
  if (!job.plan) throw FarmError(Code::FailedPrecondition, fmt::format("job {} has no plan yet", jobId));
  return *job.plan;
}

UploadReply Coordinator::upload(const std::string& workerId, const std::string& leaseId, const std::string& jobId,
                                uint32_t taskIndex, PartialResult result) {
  std::shared_ptr<const JobPlan> plan;
  JobIdentity identity;
  {
    std::lock_guard lock(mu_);
    Job& job = findJob(jobId);
    if (!job.plan) throw FarmError(Code::FailedPrecondition, fmt::format("job {} has no plan", jobId));
    if (taskIndex >= job.tasks.size())
      throw FarmError(Code::InvalidArgument,
                      fmt::format("task_index: {} out of range [0, {})", taskIndex, job.tasks.size()));
    const TaskRange range = job.tasks[taskIndex];
    if (result.film.width() != job.plan->settings.width || result.film.height() != job.plan->settings.height)
      throw FarmError(Code::InvalidArgument, fmt::format("partial.width/height: {}x{}, the job renders {}x{}",
                                                         result.film.width(), result.film.height(),
                                                         job.plan->settings.width, job.plan->settings.height));
    std::vector<uint32_t> expect;
    for (uint32_t u = range.begin; u < range.end; ++u) expect.push_back(u);
    if (result.units != expect)
      throw FarmError(Code::InvalidArgument, fmt::format("partial.units: task {} must hold units {}-{}", taskIndex,
                                                         range.begin, range.end - 1));
    if (job.status.state != JobState::Running) {
      spdlog::info("job={} task={} worker={} event=upload_ignored state={}", jobId, taskIndex, workerId,
                   jobStateName(job.status.state));
      return {false, fmt::format("job {} is {}", jobId, jobStateName(job.status.state))};
    }
    if (job.taskState[taskIndex] == TaskState::Accepted) {
      spdlog::warn("job={} task={} worker={} lease={} event=duplicate_dropped", jobId, taskIndex, workerId, leaseId);
      return {false, fmt::format("task {} of {} was already accepted", taskIndex, jobId)};
    }
    // Persist before acknowledging: nothing accepted is lost.
    store_->insertResult(job.rec.id, taskIndex, wire::serializePartial(result));
    job.taskState[taskIndex] = TaskState::Accepted;
    for (auto it = leases_.begin(); it != leases_.end();)
      it = (it->second.job == job.rec.id && it->second.task == taskIndex) ? leases_.erase(it) : std::next(it);
    std::erase(job.pending, taskIndex);
    refreshProgress(job);
    spdlog::info("job={} task={} units={}-{} worker={} lease={} event=accepted seconds={:.3f} done={}/{}", jobId,
                 taskIndex, range.begin, range.end - 1, workerId, leaseId, result.seconds, job.status.tasksDone,
                 job.status.tasksTotal);
    if (job.status.tasksDone == job.tasks.size()) {
      setState(job, JobState::Merging);
      work_.notify_all();
    } else {
      touch(job);
    }
    plan = job.plan;
    identity = {job.status.jobId, job.rec.sceneHash, job.rec.sceneFile};
  }
  if (opt_.keepPartials) {
    fs::path dir = fs::path(jobDir(parseJobId(jobId))) / "partials";
    fs::create_directories(dir);
    std::string path = (dir / fmt::format("task-{:04}.exr", taskIndex)).string();
    writePartialExr(path + ".tmp.exr", identity, *plan, taskIndex, result);
    fs::rename(path + ".tmp.exr", path);
  }
  return {true, "accepted"};
}

bool Coordinator::taskAttemptFailed(Job& job, uint32_t task, const std::string& reason) {
  // Only a task that is still leased counts: a late report for a task that has meanwhile been accepted,
  // requeued or re-leased elsewhere says nothing about the current attempt.
  job.taskState[task] = TaskState::Pending;
  const uint32_t n = ++job.attempts[task];
  ++job.status.failedAttempts;
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
    if (job != jobs_.end() && job->second.taskState[it->second.task] == TaskState::Leased) {
      job->second.taskState[it->second.task] = TaskState::Pending;
      if (job->second.status.state == JobState::Running) job->second.pending.push_front(it->second.task);
      spdlog::info("job={} task={} worker={} lease={} event=returned", job->second.status.jobId, it->second.task,
                   workerId, id);
      touch(job->second);
    }
    leases_.erase(it);
  }
}

// ---------------------------------------------------------------------------------------------
// Background: bootstrap, merge, lease expiry
// ---------------------------------------------------------------------------------------------
void Coordinator::plannerLoop() {
  std::unique_lock lock(mu_);
  while (!stopping_) {
    int64_t toMerge = -1, toPlan = -1;
    int bestPriority = 0;
    for (auto& [id, job] : jobs_) {
      if (job.status.state == JobState::Merging && toMerge < 0) toMerge = id;
      if (job.status.state == JobState::Queued && (toPlan < 0 || job.status.priority > bestPriority)) {
        toPlan = id;
        bestPriority = job.status.priority;
      }
    }
    if (toMerge >= 0) {
      lock.unlock();
      merge(toMerge);
      lock.lock();
    } else if (toPlan >= 0) {
      lock.unlock();
      planOne(toPlan);
      lock.lock();
    } else {
      work_.wait(lock);
    }
  }
}

void Coordinator::planOne(int64_t id) {
  std::string file, jobId;
  RenderSettings settings;
  std::map<std::string, std::string> defines;
  {
    std::lock_guard lock(mu_);
    Job& job = jobs_.at(id);
    if (job.status.state != JobState::Queued) return;
    setState(job, JobState::Planning);
    file = (fs::path(sceneDir(job.rec.sceneHash)) / job.rec.sceneFile).string();
    v1::RenderSettings ps;
    ps.ParseFromString(job.rec.settings);
    settings = wire::fromProto(ps).settings;
    defines = job.defines;
    jobId = job.status.jobId;
  }
  std::shared_ptr<JobPlan> plan;
  std::string error;
  try {
    auto scene = buildRenderScene(loadSceneDesc(file, defines), settings.width, settings.height);
    spdlog::info("job={} event=bootstrap_start method={} bootstrap_samples={}", jobId, settings.method,
                 settings.bootstrapSamples);
    plan = std::make_shared<JobPlan>(planJob(*scene, settings));
    spdlog::info("job={} event=bootstrap_done b={} b_stderr={} units={} seconds={:.3f}", jobId, plan->norm.b,
                 plan->norm.bStdErr, plan->units.size(), plan->norm.bootstrapSeconds);
    if (plan->units.empty()) error = "the plan has no work units";
    wire::parseJobPlan(wire::jobPlanBytes(*plan));  // the plan must survive the wire
  } catch (const std::exception& e) {
    error = e.what();
  }
  std::lock_guard lock(mu_);
  Job& job = jobs_.at(id);
  if (job.status.state != JobState::Planning) return;  // cancelled meanwhile
  if (!error.empty()) {
    setState(job, JobState::Failed, "bootstrap: " + error);
    return;
  }
  job.plan = plan;
  store_->setPlan(id, wire::jobPlanBytes(*plan), uint32_t(splitTasks(*plan).size()), int(JobState::Running));
  job.status.state = JobState::Running;
  startRunning(job);
  touch(job);
}

void Coordinator::merge(int64_t id) {
  std::shared_ptr<const JobPlan> plan;
  JobIdentity identity;
  size_t tasks = 0;
  {
    std::lock_guard lock(mu_);
    Job& job = jobs_.at(id);
    plan = job.plan;
    identity = {job.status.jobId, job.rec.sceneHash, job.rec.sceneFile};
    tasks = job.tasks.size();
  }
  std::string error;
  std::optional<RefinedB> refined;  // b as the image was developed with (bootstrap + large steps)
  try {
    PartialResult merged = emptyPartial(*plan);
    for (uint32_t t = 0; t < tasks; ++t) {  // index order: the bytes never depend on arrival order
      std::optional<std::string> blob;
      {
        std::lock_guard lock(mu_);
        blob = store_->loadResult(id, t);
      }
      if (!blob) throw std::runtime_error(fmt::format("task {} has no stored result", t));
      merged.add(wire::parsePartial(*blob));
    }
    fs::path dir = jobDir(id);
    fs::create_directories(dir);
    writeFinalImages((dir / "image.tmp.exr").string(), (dir / "image.tmp.png").string(), identity, *plan, merged);
    if (isMarkovChainMethod(plan->settings.method)) refined = refinedB(plan->norm, merged.stats);
    fs::rename(dir / "image.tmp.exr", dir / "image.exr");
    fs::rename(dir / "image.tmp.png", dir / "image.png");
  } catch (const std::exception& e) {
    error = e.what();
  }
  std::lock_guard lock(mu_);
  Job& job = jobs_.at(id);
  if (job.status.state != JobState::Merging) return;
  if (refined) {
    job.status.b = refined->total.b;
    job.status.bStdErr = refined->total.stdErr;
  }
  if (!error.empty()) setState(job, JobState::Failed, "merge: " + error);
  else setState(job, JobState::Done);
}

void Coordinator::reaperLoop() {
  std::unique_lock lock(mu_);
  while (!stopping_) {
    changed_.wait_for(lock, std::chrono::milliseconds(200));
    const auto now = Clock::now();
    for (auto it = leases_.begin(); it != leases_.end();) {
      if (it->second.deadline > now) {
        ++it;
        continue;
      }
      auto job = jobs_.find(it->second.job);
      if (job != jobs_.end() && job->second.taskState[it->second.task] == TaskState::Leased) {
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
  }
}

}  // namespace mlt::farm
