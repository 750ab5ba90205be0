// The coordinator's ClientHandler (see handler.h): submit (bundle, scene validation, record), status,
// watch, cancel, list and the finished image's path.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fmt/format.h>
#include <thread>

#include "common/core/durable_file.h"
#include "common/farm/bundle.h"
#include "common/farm/scene_loading.h"
#include "common/job/mlt_job.h"
#include "common/scene/scene_files.h"
#include "coordinator/coordinator.h"
#include "coordinator/storage_error.h"
#include "proto/convert.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

using Code = FarmError::Code;

double unixNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

constexpr double kMaxTotalWork = 1e12;  // mutations or pixel samples per job

// A submission by path: only under the coordinator's scene root (off when it has none), and the scene
// reads only files under that root (the bundle's paths are relative to it).
SceneBundle bundleFromSceneRoot(const std::string& sceneRoot, const std::string& path,
                                const std::map<std::string, std::string>& defines) {
  if (sceneRoot.empty())
    throw FarmError(Code::FailedPrecondition,
                    "coordinator_path: submitting by a path on the coordinator's disk is off (the coordinator was "
                    "started without --scene-root); upload the scene's files instead");
  const fs::path p = fs::path(sceneRoot) / path;  // an absolute `path` replaces the root
  if (!pathInsideRoot(sceneRoot, p.string()))
    throw FarmError(Code::InvalidArgument,
                    fmt::format("coordinator_path: '{}' lies outside the coordinator's scene root", clipForMessage(path)));
  return collectBundle(p.string(), defines, sceneRoot);  // the scene root is the clients' to name
}

void checkBundleQuota(const std::vector<BundleFile>& files, const SubmitQuotas& quota) {
  if (files.size() > quota.maxBundleFiles)
    throw FarmError(Code::ResourceExhausted, fmt::format("bundle: {} files exceeds the limit of {} (--max-bundle-files)",
                                                         files.size(), quota.maxBundleFiles));
  uint64_t bytes = 0;
  for (const BundleFile& f : files) bytes += f.data.size();
  if (bytes > quota.maxBundleBytes)
    throw FarmError(Code::ResourceExhausted, fmt::format("bundle: {} bytes exceeds the limit of {} (--max-bundle-bytes)",
                                                         bytes, quota.maxBundleBytes));
}

}  // namespace

bool Coordinator::sceneInUse(const std::string& hash) const {
  if (bundlesInSubmit_.count(hash)) return true;
  return std::any_of(jobs_.begin(), jobs_.end(),
                     [&](const auto& j) { return !j.second.deleted && j.second.rec.sceneHash == hash; });
}

JobStatus Coordinator::submit(SubmitRequest req) {
  try {
    return submitChecked(std::move(req));
  } catch (const FarmError& e) {  // messages never name this process's directories
    throw FarmError(e.code(), hideRoot(e.what(), opt_.stateDir));
  } catch (const std::filesystem::filesystem_error& e) {
    spdlog::error("event=submit_io_error error=\"{}\"", e.what());
    throw FarmError(Code::Internal, fmt::format("cannot store the scene: {}", e.code().message()));
  }
}

JobStatus Coordinator::submitChecked(SubmitRequest req) {
  // 0. Quotas that need no bundle.
  const SubmitQuotas& quota = opt_.quotas;
  if (req.name.size() > quota.maxJobNameBytes)
    throw FarmError(Code::InvalidArgument, fmt::format("name: {} bytes exceeds the limit of {} (--max-job-name)",
                                                       req.name.size(), quota.maxJobNameBytes));
  if (!req.client.empty()) {
    std::lock_guard lock(mu_);
    const auto unfinished = std::count_if(jobs_.begin(), jobs_.end(), [&](const auto& j) {
      // rec.client is stored with the job: the count survives a restart (recovery.cpp reloads it).
      return !j.second.deleted && j.second.rec.client == req.client && !isTerminal(j.second.status.state);
    });
    if (size_t(unfinished) >= quota.maxJobsPerClient)
      throw FarmError(Code::ResourceExhausted,
                      fmt::format("this client has {} unfinished jobs: the limit (--max-jobs-per-client) is {}",
                                  unfinished, quota.maxJobsPerClient));
  }
  // 1. The bundle: uploaded files, or collected from a path under the scene root (--scene-root).
  SceneBundle bundle;
  if (!req.coordinatorPath.empty()) {
    bundle = bundleFromSceneRoot(opt_.sceneRoot, req.coordinatorPath, req.defines);
  } else {
    if (req.bundle.empty()) throw FarmError(Code::InvalidArgument, "bundle: no scene files uploaded and no coordinator_path");
    for (const BundleFile& f : req.bundle) validateBundlePath(f.path);
    validateBundlePath(req.bundleSceneFile);
    if (std::none_of(req.bundle.begin(), req.bundle.end(), [&](auto& f) { return f.path == req.bundleSceneFile; }))
      throw FarmError(Code::InvalidArgument, fmt::format("bundle_scene_file: '{}' is not in the uploaded bundle",
                                                         clipForMessage(req.bundleSceneFile)));
    bundle.files = std::move(req.bundle);
    bundle.sceneFile = req.bundleSceneFile;
  }
  checkBundleQuota(bundle.files, quota);
  const std::string hash = bundleHash(bundle.files);
  if (!req.bundleHash.empty() && req.bundleHash != hash)
    throw FarmError(Code::InvalidArgument, fmt::format("bundle_hash: client says {}, the uploaded files hash to {}",
                                                       clipForMessage(req.bundleHash), hash));
  const std::string dir = sceneDir(hash);
  // A rejected bundle is deleted (unless a job or another submission uses the same files).
  struct BundleInSubmit {
    Coordinator& c;
    const std::string& hash;
    const std::string& dir;
    const int exceptions = std::uncaught_exceptions();
    BundleInSubmit(Coordinator& co, const std::string& h, const std::string& d) : c(co), hash(h), dir(d) {
      std::lock_guard lock(c.mu_);
      ++c.bundlesInSubmit_[hash];
    }
    ~BundleInSubmit() {
      std::lock_guard lock(c.mu_);
      if (--c.bundlesInSubmit_[hash] == 0) c.bundlesInSubmit_.erase(hash);
      std::error_code ec;
      if (std::uncaught_exceptions() > exceptions && !c.sceneInUse(hash)) fs::remove_all(dir, ec);
    }
  } inSubmit(*this, hash, dir);
  if (!fs::exists(dir)) {
    std::string tmp = dir + ".tmp-" + instance_ + fmt::format("-{}", std::hash<std::thread::id>()(std::this_thread::get_id()));
    try {
      fs::remove_all(tmp);
      writeBundle(tmp, bundle.files);
    } catch (const std::exception& e) {  // disk full or read-only: RESOURCE_EXHAUSTED / UNAVAILABLE
      const int err = errno;
      std::error_code ec;
      fs::remove_all(tmp, ec);
      throw storageError(fmt::format("bundle {}: {}", hash.substr(0, 12), e.what()), err);
    }
    std::error_code ec;
    fs::rename(tmp, dir, ec);  // another submit of the same bundle may have won: same bytes
    if (ec) fs::remove_all(tmp, ec);
    else syncDirectory(fs::path(dir).parent_path().string());  // the rename is on disk before the job is
  }
  // 2. Load and validate the scene exactly as the workers will: from the bundle's files only.
  SceneDesc desc;
  try {
    desc = loadSceneDesc((fs::path(dir) / bundle.sceneFile).string(), req.defines, dir);
  } catch (const FarmError& e) {
    throw FarmError(e.code(), "scene: " + std::string(e.what()));
  }
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
  // Every value as the planner and the workers will read it back: a scene may carry values the wire
  // refuses (a 65536 px film, sample_count 2^30, max_depth 2000; the plan's limits are 16384, 2^20, 1024).
  // Checked once, here, against exactly those limits, so the job is refused now, naming the field.
  const wire::SubmittedSettings resolved{s, true, true, true, true, req.defines};
  try {
    wire::fromProto(wire::toProto(resolved));
  } catch (const wire::WireError& e) {
    throw FarmError(Code::InvalidArgument, fmt::format("{} (as submitted, or taken from the scene {} where not given)",
                                                       e.what(), bundle.sceneFile));
  }
  try {
    buildRenderScene(desc, s.width, s.height);  // throws InvalidArgument naming the element
  } catch (const FarmError& e) {
    throw FarmError(e.code(), hideRoot(e.what(), dir));
  }

  // 3. Record it.
  std::lock_guard lock(mu_);
  JobRecord rec;
  rec.name = req.name;
  rec.priority = req.priority;
  rec.state = int(JobState::Queued);
  rec.settings = wire::toProto(resolved).SerializeAsString();
  rec.sceneHash = hash;
  rec.sceneFile = bundle.sceneFile;
  rec.submittedAt = unixNow();
  rec.client = req.client;
  rec.id = store_->insertJob(rec);
  metrics_.jobsSubmitted.Increment();
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
    if (job.deleted) continue;
    refreshProgress(job);
    out.push_back(job.status);
    out.back().elapsedSeconds = unixNow() - job.rec.submittedAt;
  }
  return out;
}

void Coordinator::deleteJob(const std::string& jobId) {
  std::lock_guard lock(mu_);
  Job& job = findJob(jobId);
  if (!isTerminal(job.status.state))
    throw FarmError(Code::FailedPrecondition,
                    fmt::format("job {} is {}: cancel it before deleting it", jobId, jobStateName(job.status.state)));
  store_->deleteJob(job.rec.id);
  // Threads that still hold the id (a planner or merge that saw the job cancelled) find it, terminal.
  job.deleted = true;
  for (auto it = leases_.begin(); it != leases_.end();) it = it->second.job == job.rec.id ? leases_.erase(it) : std::next(it);
  std::error_code ec;
  fs::remove_all(jobDir(job.rec.id), ec);
  if (ec) spdlog::warn("job={} event=delete_files error=\"{}\"", jobId, ec.message());
  if (!sceneInUse(job.rec.sceneHash)) fs::remove_all(sceneDir(job.rec.sceneHash), ec);
  spdlog::info("job={} event=deleted", jobId);
  touch(job);
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

}  // namespace mlt::farm
