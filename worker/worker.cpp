// The worker loop (see worker.h).
#include "worker/worker.h"

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fmt/format.h>
#include <random>

#include "coordinator/bundle.h"
#include "coordinator/merge.h"
#include "coordinator/convert.h"
#include "coordinator/scene_loading.h"
#include "proto/convert.h"
#include "worker/uploader.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

bool transient(grpc::StatusCode c) {
  return c == grpc::UNAVAILABLE || c == grpc::DEADLINE_EXCEEDED || c == grpc::CANCELLED || c == grpc::UNKNOWN ||
         c == grpc::INTERNAL || c == grpc::RESOURCE_EXHAUSTED;
}

std::string hostName() {
  char buf[256] = {};
  gethostname(buf, sizeof(buf) - 1);
  return buf;
}

}  // namespace

Worker::Worker(WorkerOptions options) : opt_(std::move(options)) {
  if (opt_.threads <= 0) opt_.threads = int(std::max(1u, std::thread::hardware_concurrency()));
  if (opt_.cacheDir.empty())
    opt_.cacheDir = (fs::temp_directory_path() / fmt::format("mltfarm-worker-cache-{}", getuid())).string();
  fs::create_directories(opt_.cacheDir);
  channel_ = makeChannel(opt_.coordinator);
  stub_ = v1::WorkerService::NewStub(channel_);
}

Worker::~Worker() {
  stop_ = true;
  for (auto& a : active_) {
    a->cancel = true;
    if (a->thread.joinable()) a->thread.join();
  }
}

void Worker::backoff(int& attempt) {
  // 100 ms doubling to 5 s, with jitter so a restarted coordinator is not hit by every worker at once.
  static thread_local std::mt19937 rng{std::random_device{}()};
  double ms = std::min(5000.0, 100.0 * double(1 << std::min(attempt, 6)));
  ms *= std::uniform_real_distribution<double>(0.5, 1.0)(rng);
  ++attempt;
  for (double slept = 0; slept < ms && !stop_; slept += 20) std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

bool Worker::registerWithBackoff() {
  int attempt = 0;
  while (!stop_) {
    grpc::ClientContext ctx;
    prepareContext(ctx, opt_.coordinator, std::chrono::seconds(10));
    v1::RegisterRequest req;
    req.set_format_version(wire::kFormatVersion);
    req.set_hostname(hostName());
    req.set_threads(opt_.threads);
    req.set_pid(getpid());
    v1::RegisterResponse resp;
    grpc::Status s = stub_->Register(&ctx, req, &resp);
    if (s.ok()) {
      std::lock_guard lock(mu_);
      workerId_ = resp.worker_id();
      heartbeatSeconds_ = resp.heartbeat_interval_seconds();
      spdlog::info("worker={} event=registered coordinator={} threads={}", workerId_, opt_.coordinator.address,
                   opt_.threads);
      reregister_ = false;
      return true;
    }
    if (!transient(s.error_code())) {
      spdlog::error("event=register_failed status={} message=\"{}\"", statusCodeName(s.error_code()), s.error_message());
      return false;
    }
    spdlog::warn("event=coordinator_unavailable attempt={} message=\"{}\"", attempt, s.error_message());
    backoff(attempt);
  }
  return false;
}

void Worker::heartbeatLoop() {
  while (!stop_) {
    double interval;
    std::string id;
    std::vector<std::string> leases;
    {
      std::lock_guard lock(mu_);
      interval = heartbeatSeconds_;
      id = workerId_;
      for (auto& a : active_)
        if (!a->finished) leases.push_back(a->lease.leaseId);
    }
    grpc::ClientContext ctx;
    prepareContext(ctx, opt_.coordinator, std::chrono::milliseconds(int(std::max(1.0, 2 * interval) * 1000)));
    v1::HeartbeatRequest req;
    req.set_format_version(wire::kFormatVersion);
    req.set_worker_id(id);
    for (auto& l : leases) req.add_lease_ids(l);
    v1::HeartbeatResponse resp;
    grpc::Status s = stub_->Heartbeat(&ctx, req, &resp);
    if (s.ok()) {
      if (resp.unknown_worker()) reregister_ = true;
      std::lock_guard lock(mu_);
      for (const std::string& c : resp.cancelled_lease_ids())
        for (auto& a : active_)
          if (a->lease.leaseId == c && !a->cancel.exchange(true))
            spdlog::info("worker={} job={} task={} lease={} event=cancelled_by_coordinator", workerId_, a->lease.jobId,
                         a->lease.taskIndex, c);
    }
    for (double slept = 0; slept < interval && !stop_; slept += 0.02)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::shared_ptr<const JobPlan> Worker::planFor(const std::string& jobId) {
  {
    std::lock_guard lock(mu_);
    if (auto it = plans_.find(jobId); it != plans_.end()) return it->second;
  }
  auto plan = std::make_shared<const JobPlan>(fetchPlan(*stub_, opt_.coordinator, jobId));
  std::lock_guard lock(mu_);
  return plans_.emplace(jobId, plan).first->second;
}

std::shared_ptr<const RenderScene> Worker::sceneFor(const Lease& l, const JobPlan& plan) {
  std::string key = fmt::format("{}@{}x{}", l.sceneHash, plan.settings.width, plan.settings.height);
  for (const auto& [name, value] : l.defines) key += fmt::format("|{}={}", name, value);
  std::shared_ptr<SceneEntry> entry;
  {
    std::lock_guard lock(mu_);
    auto& e = scenes_[key];
    if (!e) e = std::make_shared<SceneEntry>();
    entry = e;
  }
  std::lock_guard lock(entry->mu);  // one thread fetches and builds; the others wait for it
  if (entry->scene) return entry->scene;
  const fs::path dir = fs::path(opt_.cacheDir) / l.sceneHash;
  if (!fs::exists(dir)) {
    std::vector<BundleFile> files = fetchScene(*stub_, opt_.coordinator, l.sceneHash);
    const fs::path tmp = dir.string() + fmt::format(".tmp-{}", getpid());
    fs::remove_all(tmp);
    writeBundle(tmp.string(), files);
    std::error_code ec;
    fs::rename(tmp, dir, ec);  // another worker on this machine may have won: same bytes
    if (ec) fs::remove_all(tmp);
    spdlog::info("event=scene_cached scene_hash={} files={}", l.sceneHash.substr(0, 12), files.size());
  }
  SceneDesc desc = loadSceneDesc((dir / l.sceneFile).string(), l.defines);
  entry->scene = buildRenderScene(std::move(desc), plan.settings.width, plan.settings.height);
  return entry->scene;
}

void Worker::runTask(Active* a) {
  const Lease& l = a->lease;
  std::string workerId;
  {
    std::lock_guard lock(mu_);
    workerId = workerId_;
  }
  try {
    auto plan = planFor(l.jobId);
    auto scene = sceneFor(l, *plan);
    for (int slept = 0; slept < opt_.taskDelayMs && !a->cancel; slept += 10)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (opt_.failUnit >= int64_t(l.unitBegin) && opt_.failUnit < int64_t(l.unitEnd))
      throw std::runtime_error(fmt::format("debug: work unit {} fails on purpose (--debug-fail-unit)", opt_.failUnit));
    const auto t0 = std::chrono::steady_clock::now();
    PartialResult result;
    if (!farm::runTask(*scene, *plan, {l.unitBegin, l.unitEnd}, result, &a->cancel)) {
      spdlog::info("worker={} job={} task={} event=abandoned", workerId, l.jobId, l.taskIndex);
      releaseSlot(a);
      a->finished = true;
      return;
    }
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // The compute slot is free while the film uploads (and the coordinator stores it): lease the next task
    // now so that a core never waits on the network.
    releaseSlot(a);
    int attempt = 0;
    while (true) {
      try {
        UploadReply r = uploadPartial(*stub_, opt_.coordinator, {workerId, l.leaseId, l.jobId, l.taskIndex}, result);
        spdlog::info("worker={} job={} task={} units={}-{} lease={} event=uploaded accepted={} seconds={:.3f} message=\"{}\"",
                     workerId, l.jobId, l.taskIndex, l.unitBegin, l.unitEnd - 1, l.leaseId, r.accepted, result.seconds,
                     r.message);
        break;
      } catch (const RpcError& e) {
        if (!transient(e.code()) || attempt > 12 || (stop_ && !opt_.drain)) throw;
        spdlog::warn("worker={} job={} task={} event=upload_retry attempt={} error=\"{}\"", workerId, l.jobId,
                     l.taskIndex, attempt, e.what());
        backoff(attempt);
      }
    }
  } catch (const std::exception& e) {
    spdlog::error("worker={} job={} task={} lease={} event=task_failed error=\"{}\"", workerId, l.jobId, l.taskIndex,
                  l.leaseId, e.what());
    // A coordinator that cannot be reached gets no report: the lease expires there and is counted then.
    const auto* rpc = dynamic_cast<const RpcError*>(&e);
    if (!a->cancel && !(rpc && transient(rpc->code()))) reportFailure(l, workerId, e.what());
  }
  releaseSlot(a);
  a->finished = true;
  slotFreed_.notify_all();
}

void Worker::releaseSlot(Active* a) {
  {
    std::lock_guard lock(mu_);
    a->computing = false;
  }
  slotFreed_.notify_all();
}

void Worker::reportFailure(const Lease& l, const std::string& workerId, const std::string& message) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_.coordinator, std::chrono::seconds(10));
  v1::ReportFailureRequest req;
  req.set_format_version(wire::kFormatVersion);
  req.set_worker_id(workerId);
  req.set_lease_id(l.leaseId);
  req.set_job_id(l.jobId);
  req.set_task_index(l.taskIndex);
  req.set_message(message.substr(0, 60 * 1024));
  v1::ReportFailureResponse resp;
  grpc::Status s = stub_->ReportFailure(&ctx, req, &resp);
  spdlog::info("worker={} job={} task={} lease={} event=failure_reported ok={} job_failed={}", workerId, l.jobId,
               l.taskIndex, l.leaseId, s.ok(), resp.job_failed());
}

void Worker::reapFinished() {
  std::lock_guard lock(mu_);
  for (auto it = active_.begin(); it != active_.end();) {
    if ((*it)->finished) {
      if ((*it)->thread.joinable()) (*it)->thread.join();
      it = active_.erase(it);
    } else {
      ++it;
    }
  }
}

int Worker::run() {
  // Units may use TBB inside; never more threads than we were given.
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(opt_.threads));
  if (!registerWithBackoff()) return stop_ ? 0 : 1;
  std::thread heartbeat([this] { heartbeatLoop(); });
  int attempt = 0;
  while (!stop_) {
    reapFinished();
    if (reregister_ && !registerWithBackoff()) break;
    int free;
    std::string id;
    {
      std::unique_lock lock(mu_);
      auto computing = [this] {
        int n = 0;
        for (const auto& a : active_) n += a->computing ? 1 : 0;
        return n;
      };
      // Woken as soon as a task's film is made (releaseSlot), not by polling.
      slotFreed_.wait_for(lock, std::chrono::milliseconds(200),
                          [&] { return stop_ || opt_.threads - computing() > 0; });
      free = opt_.threads - computing();
      id = workerId_;
    }
    if (stop_) break;
    if (free <= 0) continue;
    grpc::ClientContext ctx;
    prepareContext(ctx, opt_.coordinator, std::chrono::seconds(10));
    v1::LeaseRequest req;
    req.set_format_version(wire::kFormatVersion);
    req.set_worker_id(id);
    req.set_max_tasks(free);
    v1::LeaseResponse resp;
    grpc::Status s = stub_->LeaseWork(&ctx, req, &resp);
    if (!s.ok()) {
      if (s.error_code() == grpc::FAILED_PRECONDITION) {
        reregister_ = true;  // the coordinator restarted and forgot us
        continue;
      }
      if (!transient(s.error_code())) {
        spdlog::error("worker={} event=lease_failed status={} message=\"{}\"", id, statusCodeName(s.error_code()),
                      s.error_message());
        stop_ = true;
        break;
      }
      spdlog::warn("worker={} event=coordinator_unavailable attempt={} message=\"{}\"", id, attempt, s.error_message());
      backoff(attempt);
      continue;
    }
    attempt = 0;
    for (const auto& pl : resp.leases()) {
      auto a = std::make_unique<Active>();
      a->lease = fromProto(pl);
      Active* raw = a.get();
      std::lock_guard lock(mu_);
      active_.push_back(std::move(a));
      raw->thread = std::thread([this, raw] { runTask(raw); });
    }
    if (resp.leases().empty()) {
      const double wait = std::clamp(resp.retry_after_seconds(), 0.02, 5.0);
      for (double slept = 0; slept < wait && !stop_; slept += 0.02)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  // Shutting down: return (or finish, with --drain) what we hold.
  std::vector<std::string> returned;
  {
    std::lock_guard lock(mu_);
    for (auto& a : active_)
      if (!a->finished && !opt_.drain) {
        a->cancel = true;
        returned.push_back(a->lease.leaseId);
      }
  }
  if (!returned.empty()) {
    grpc::ClientContext ctx;
    prepareContext(ctx, opt_.coordinator, std::chrono::seconds(5));
    v1::ReturnLeaseRequest req;
    req.set_format_version(wire::kFormatVersion);
    req.set_worker_id(workerId_);
    for (auto& l : returned) req.add_lease_ids(l);
    v1::ReturnLeaseResponse resp;
    grpc::Status s = stub_->ReturnLeases(&ctx, req, &resp);
    spdlog::info("worker={} event=leases_returned count={} ok={}", workerId_, returned.size(), s.ok());
  }
  for (auto& a : active_)
    if (a->thread.joinable()) a->thread.join();
  active_.clear();
  heartbeat.join();
  spdlog::info("worker={} event=stopped", workerId_);
  return 0;
}

}  // namespace mlt::farm
