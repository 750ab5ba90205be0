// The worker loop (see worker.h).
#include "worker/worker.h"

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fmt/format.h>
#include <random>

#include "common/farm/tasks.h"
#include "common/job/executor.h"

namespace fs = std::filesystem;

namespace mlt::farm {
namespace {

std::string hostName() {
  char buf[256] = {};
  gethostname(buf, sizeof(buf) - 1);
  return buf;
}

WorkerOptions withDefaults(WorkerOptions o) {
  if (o.threads <= 0) o.threads = int(std::max(1u, std::thread::hardware_concurrency()));
  if (o.cacheDir.empty())
    o.cacheDir = (fs::temp_directory_path() / fmt::format("mltfarm-worker-cache-{}", getuid())).string();
  if (o.spoolDir.empty()) o.spoolDir = (fs::path(o.cacheDir) / "spool").string();
  return o;
}

}  // namespace

Worker::Worker(WorkerOptions options)
    : opt_(withDefaults(std::move(options))),
      client_(opt_.coordinator),
      scenes_(opt_.cacheDir, [this](const std::string& hash) { return fetchBundle(hash); }, opt_.cacheMaxBytes),
      plans_("plans", opt_.planCacheMaxBytes) {}

namespace {
thread_local bool tFetchedBundle = false;  // set when this thread's scene lookup had to fetch the bundle
}  // namespace

std::vector<BundleFile> Worker::fetchBundle(const std::string& hash) {
  std::vector<BundleFile> files = client_.scene(hash);
  tFetchedBundle = true;
  uint64_t bytes = 0;
  for (const BundleFile& f : files) bytes += f.data.size();
  metrics_.downloadBytes.Increment(double(bytes));
  return files;
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
    try {
      Registration r = client_.registerWorker({hostName(), opt_.threads, getpid()});
      std::lock_guard lock(mu_);
      workerId_ = r.workerId;
      heartbeatSeconds_ = r.heartbeatSeconds;
      spdlog::info("worker={} event=registered coordinator={} threads={}", workerId_, opt_.coordinator.address,
                   opt_.threads);
      reregister_ = false;
      return true;
    } catch (const RpcError& e) {
      if (!isTransient(e.code())) {
        spdlog::error("event=register_failed status={} message=\"{}\"", statusCodeName(e.code()), e.message());
        return false;
      }
      spdlog::warn("event=coordinator_unavailable attempt={} message=\"{}\"", attempt, e.message());
    }
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
    if (spool_)  // spooled films keep their leases, so that nobody else is given their tasks meanwhile
      for (std::string& l : spool_->leaseIds(id)) leases.push_back(std::move(l));
    try {
      HeartbeatReply r =
          client_.heartbeat(id, leases, std::chrono::milliseconds(int(std::max(1.0, 2 * interval) * 1000)));
      if (r.unknownWorker) reregister_ = true;
      std::lock_guard lock(mu_);
      for (const std::string& c : r.cancelledLeases)
        for (auto& a : active_)
          if (a->lease.leaseId == c && !a->cancel.exchange(true))
            spdlog::info("worker={} job={} task={} lease={} event=cancelled_by_coordinator", workerId_, a->lease.jobId,
                         a->lease.taskIndex, c);
    } catch (const RpcError&) {
      // The coordinator is away: the lease loop backs off and registers again; nothing to do here.
    }
    for (double slept = 0; slept < interval && !stop_; slept += 0.02)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::shared_ptr<const JobPlan> Worker::planFor(const std::string& jobId) {
  bool fetched = false;
  auto plan = plans_.get(jobId, [&] {
    uint64_t bytes = 0;
    auto p = std::make_shared<const JobPlan>(client_.plan(jobId, &bytes));
    fetched = true;
    metrics_.downloadBytes.Increment(double(bytes));
    return std::pair{std::move(p), bytes};
  });
  (fetched ? metrics_.planCacheMisses : metrics_.planCacheHits).Increment();
  return plan;
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
    tFetchedBundle = false;
    auto scene = scenes_.get(l.sceneHash, l.sceneFile, l.defines, plan->settings.width, plan->settings.height);
    (tFetchedBundle ? metrics_.sceneCacheMisses : metrics_.sceneCacheHits).Increment();
    for (int slept = 0; slept < opt_.taskDelayMs && !a->cancel; slept += 10)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (opt_.failUnit >= int64_t(l.unitBegin) && opt_.failUnit < int64_t(l.unitEnd))
      throw std::runtime_error(fmt::format("debug: work unit {} fails on purpose (--debug-fail-unit)", opt_.failUnit));
    const auto t0 = std::chrono::steady_clock::now();
    PartialResult result;
    // Up to every thread on this task's units, inside the worker's one arena of `threads` slots: the tasks
    // in hand share the threads unit by unit (never more runnable threads than cores), and the job's last
    // task does not leave the other threads idle (with as many units in flight as the in-process
    // renderer: executor.h unitsInFlight).
    bool complete = false;
    arena_->execute([&] {
      complete = farm::runTask(*scene, *plan, {l.unitBegin, l.unitEnd}, result, &a->cancel,
                               unitsInFlight(size_t(opt_.threads)));
    });
    if (!complete) {
      spdlog::info("worker={} job={} task={} event=abandoned", workerId, l.jobId, l.taskIndex);
      metrics_.tasksAbandoned.Increment();
      metrics_.tasksRunning.Decrement();
      releaseSlot(a);
      a->finished = true;
      return;
    }
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    metrics_.taskSeconds.Observe(result.seconds);
    // The compute slot is free while the film uploads (and the coordinator stores it): lease the next task
    // now so that a core never waits on the network.
    releaseSlot(a);
    int attempt = 0;
    const UploadTarget target{workerId, l.leaseId, l.jobId, l.taskIndex};
    while (true) {
      try {
        uint64_t bytes = 0;
        UploadReply r = client_.upload(target, result, &bytes);
        metrics_.uploadBytes.Increment(double(bytes));
        metrics_.tasksUploaded.Increment();
        spdlog::info("worker={} job={} task={} units={}-{} lease={} event=uploaded accepted={} seconds={:.3f} message=\"{}\"",
                     workerId, l.jobId, l.taskIndex, l.unitBegin, l.unitEnd - 1, l.leaseId, r.accepted, result.seconds,
                     r.message);
        break;
      } catch (const RpcError& e) {
        if (!isTransient(e.code())) throw;
        // The coordinator is away: the film waits on disk, however long, and goes up when it answers again.
        if (spool_ && spool_->put(target, result)) {
          spooled_.notify_all();
          break;
        }
        if (attempt > 12 || (stop_ && !opt_.drain)) throw;  // no room in the spool: retried from memory
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
    (a->cancel ? metrics_.tasksAbandoned : metrics_.tasksFailed).Increment();
    if (!a->cancel && !(rpc && isTransient(rpc->code()))) reportFailure(l, workerId, e.what());
  }
  metrics_.tasksRunning.Decrement();
  releaseSlot(a);
  a->finished = true;
  slotFreed_.notify_all();
}

FilmSpool::Outcome Worker::uploadSpooled(const UploadTarget& t, const PartialResult& r) {
  try {
    uint64_t bytes = 0;
    UploadReply reply = client_.upload(t, r, &bytes);
    metrics_.uploadBytes.Increment(double(bytes));
    metrics_.tasksUploaded.Increment();
    spdlog::info("worker={} job={} task={} lease={} event=uploaded_from_spool accepted={} message=\"{}\"", t.workerId,
                 t.jobId, t.taskIndex, t.leaseId, reply.accepted, reply.message);
    return FilmSpool::Outcome::Done;
  } catch (const RpcError& e) {
    if (isTransient(e.code())) return FilmSpool::Outcome::Retry;
    // Refused for good: the lease was given away, the task accepted from another worker, the job is over.
    spdlog::warn("worker={} job={} task={} lease={} event=spool_refused status={} message=\"{}\"", t.workerId,
                 t.jobId, t.taskIndex, t.leaseId, statusCodeName(e.code()), e.message());
    return FilmSpool::Outcome::Done;
  }
}

void Worker::spoolLoop() {
  auto upload = [this](const UploadTarget& t, const PartialResult& r) { return uploadSpooled(t, r); };
  int attempt = 0;
  while (!stop_) {
    if (spool_->size() == 0) {
      attempt = 0;
      std::unique_lock lock(mu_);
      spooled_.wait_for(lock, std::chrono::milliseconds(500));
      continue;
    }
    spool_->drain(upload);
    if (spool_->size() > 0) backoff(attempt);
    else attempt = 0;
  }
}

void Worker::releaseSlot(Active* a) {
  {
    std::lock_guard lock(mu_);
    a->computing = false;
  }
  slotFreed_.notify_all();
}

void Worker::reportFailure(const Lease& l, const std::string& workerId, const std::string& message) {
  bool ok = true;
  FailureReply r;
  try {
    r = client_.reportFailure(workerId, l, message);
  } catch (const RpcError&) {
    ok = false;  // the lease expires on the coordinator and is counted there
  }
  spdlog::info("worker={} job={} task={} lease={} event=failure_reported ok={} job_failed={}", workerId, l.jobId,
               l.taskIndex, l.leaseId, ok, r.jobFailed);
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
  // A task's units run inside arena_, whose `threads` slots bound the threads at work. TBB counts one
  // external thread in this limit, so threads + 1 lets it give the arena `threads` worker threads for the
  // slots that task threads leave (an arena without reserved slots asks for that many, below; with a
  // limit of `threads` TBB warns on stderr that it ignores the request). Outside the arena, the one TBB
  // user is a scene's first build (Embree), once per scene per worker, which may use threads + 1.
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(opt_.threads) + 1);
  // No slot reserved for external threads. The tasks' threads are external to TBB, and TBB's worker may
  // only take an unreserved slot. With the default (one of the two slots reserved), a task thread that
  // had taken the unreserved slot kept TBB's worker out for as long as it stayed: when it was the job's
  // last task, it ran its units on one core while the other idled (per-thread perf of the README's job:
  // 2.2 s of one thread alone; some runs used 1.7-1.9 of 2 cores). With every slot open, TBB's worker
  // takes whichever slot a task thread leaves.
  arena_ = std::make_unique<tbb::task_arena>(opt_.threads, 0);
  if (opt_.spoolMaxBytes > 0) spool_ = std::make_unique<FilmSpool>(opt_.spoolDir, opt_.spoolMaxBytes);
  std::thread spooler;
  if (spool_) spooler = std::thread([this] { spoolLoop(); });
  if (!registerWithBackoff()) {
    const int rc = stop_ ? 0 : 1;
    stop_ = true;
    spooled_.notify_all();
    if (spooler.joinable()) spooler.join();
    return rc;
  }
  // Films spooled while the coordinator was away (by this process or one before it on the same spool
  // directory) go up before new work is leased: their tasks are not given to anyone else meanwhile.
  if (spool_) spool_->drain([this](const UploadTarget& t, const PartialResult& r) { return uploadSpooled(t, r); });
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
    LeaseBatch batch;
    try {
      batch = client_.lease(id, free);
    } catch (const RpcError& e) {
      if (e.code() == grpc::FAILED_PRECONDITION) {
        reregister_ = true;  // the coordinator restarted and forgot us
        continue;
      }
      if (!isTransient(e.code())) {
        spdlog::error("worker={} event=lease_failed status={} message=\"{}\"", id, statusCodeName(e.code()),
                      e.message());
        stop_ = true;
        break;
      }
      spdlog::warn("worker={} event=coordinator_unavailable attempt={} message=\"{}\"", id, attempt, e.message());
      backoff(attempt);
      continue;
    }
    attempt = 0;
    for (Lease& lease : batch.leases) {
      auto a = std::make_unique<Active>();
      a->lease = std::move(lease);
      Active* raw = a.get();
      metrics_.tasksRunning.Increment();
      std::lock_guard lock(mu_);
      active_.push_back(std::move(a));
      raw->thread = std::thread([this, raw] { runTask(raw); });
    }
    if (batch.leases.empty()) {
      const double wait = std::clamp(batch.retryAfterSeconds, 0.02, 5.0);
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
    bool ok = true;
    try {
      client_.returnLeases(workerId_, returned);
    } catch (const RpcError&) {
      ok = false;  // they expire on the coordinator instead
    }
    spdlog::info("worker={} event=leases_returned count={} ok={}", workerId_, returned.size(), ok);
  }
  for (auto& a : active_)
    if (a->thread.joinable()) a->thread.join();
  active_.clear();
  heartbeat.join();
  spooled_.notify_all();
  if (spooler.joinable()) spooler.join();
  if (spool_ && spool_->size() > 0)
    spdlog::warn("worker={} event=stopped_with_spooled_films count={} dir={} (the next worker on it uploads them)",
                 workerId_, spool_->size(), opt_.spoolDir);
  spdlog::info("worker={} event=stopped", workerId_);
  return 0;
}

}  // namespace mlt::farm
