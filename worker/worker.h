// The worker process's loop: register with the coordinator (workers dial it), lease tasks up to its
// thread count, run each task (its work units in index order) on its own thread, upload the partial
// film, heartbeat the leases it holds. Scenes are cached by content hash (on disk and built in memory),
// plans by job. When the coordinator is away it retries with exponential backoff and registers again
// after a coordinator restart; films finished meanwhile wait in a spool on disk (worker/spool.h) and are
// uploaded when it answers again. A heartbeat that names a lease as cancelled (given away after it
// expired, its task accepted elsewhere, its job over) makes the worker abandon that task. stop() (SIGTERM) stops leasing, abandons unfinished tasks between work
// units and returns their leases so other workers pick them up at once.
#pragma once
#include <tbb/task_arena.h>

#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/farm/farm_types.h"
#include "common/farm/lru_map.h"
#include "common/farm/scene_cache.h"
#include "common/methods/registry.h"
#include "common/render/render_scene.h"
#include "worker/coordinator_client.h"
#include "worker/spool.h"
#include "worker/metrics.h"

namespace mlt::farm {

struct WorkerOptions {
  ChannelOptions coordinator;
  int threads = 0;          // parallel tasks; 0 = hardware concurrency
  std::string cacheDir;     // scene bundles by hash; default $TMPDIR/mltfarm-worker-cache
  // Bounds of the caches (common/farm/scene_cache.h): bundles on disk plus built scenes in memory, and job
  // plans in memory; least recently used entries no running task holds are evicted past them. Both > 0.
  uint64_t cacheMaxBytes = SceneCache::kDefaultMaxBytes;
  uint64_t planCacheMaxBytes = 256ull << 20;
  bool drain = false;       // on stop: finish the tasks in hand instead of returning them
  // Finished films the coordinator could not take (it is away) wait here and are uploaded when it answers
  // again (worker/spool.h); default <cacheDir>/spool. At most spoolMaxBytes on disk (0: no spool).
  std::string spoolDir;
  uint64_t spoolMaxBytes = 1ull << 30;
  int taskDelayMs = 0;      // tests only: hold each lease this long before running it
  int64_t failUnit = -1;    // tests only: a task holding this work unit throws instead of running
};

class Worker {
 public:
  explicit Worker(WorkerOptions options);
  ~Worker();
  // Runs until stop() is called; returns the process exit code.
  int run();
  void stop() { stop_ = true; }
  // Counted always; served by mltfarm-worker --metrics-listen (worker/metrics.h).
  WorkerMetrics& metrics() { return metrics_; }

 private:
  struct Active {
    Lease lease;
    std::atomic<bool> cancel{false};
    std::atomic<bool> computing{true};  // holds a compute slot; false once the film is made (upload runs on)
    std::atomic<bool> finished{false};
    std::thread thread;
  };
  bool registerWithBackoff();
  std::vector<BundleFile> fetchBundle(const std::string& hash);  // the scene cache's fetch (counted)
  void heartbeatLoop();
  void runTask(Active* a);
  std::shared_ptr<const JobPlan> planFor(const std::string& jobId);
  void reportFailure(const Lease& l, const std::string& workerId, const std::string& message);
  void reapFinished();
  void releaseSlot(Active* a);  // the task no longer computes: its slot may take the next lease
  void backoff(int& attempt);
  void spoolLoop();  // uploads spooled films whenever the coordinator answers
  FilmSpool::Outcome uploadSpooled(const UploadTarget& t, const PartialResult& r);

  WorkerOptions opt_;
  WorkerMetrics metrics_;
  CoordinatorClient client_;
  SceneCache scenes_;  // bundles by hash on disk, built render scenes in memory
  std::atomic<bool> stop_{false};
  std::atomic<bool> reregister_{false};
  std::mutex mu_;  // guards workerId_, active_
  std::condition_variable slotFreed_;  // a task stopped computing or finished: lease the next one now
  std::string workerId_;
  double heartbeatSeconds_ = 1;
  std::vector<std::unique_ptr<Active>> active_;
  LruMap<JobPlan> plans_;  // by job id; a plan is in use while a task holds it
  std::unique_ptr<FilmSpool> spool_;    // null when spoolMaxBytes is 0
  std::condition_variable spooled_;     // a film was spooled (guarded by mu_)
  std::unique_ptr<tbb::task_arena> arena_;  // every task's units run here: at most `threads` at once
};

}  // namespace mlt::farm
