// The coordinator's state machine, behind the two handler interfaces:
//   submit -> load + validate the scene -> Queued -> (planner thread) planJob = bootstrap -> Running:
//   tasks leased FIFO within priorities (higher priority first, then submission order), leases renewed
//   by heartbeats and requeued when they time out -> each task accepted once, keyed by (job, task),
//   persisted (result_store.h) before it is acknowledged and summed in memory in task order as soon as
//   the tasks before it are in -> Merging (develop the sum) -> Done (EXR + PNG).
// Restarted on the same state directory it reloads every job, its plan and its accepted tasks, and
// continues where it stopped. One file per role: client_handler.cpp, worker_handler.cpp, upload.cpp,
// planner.cpp, merge_job.cpp, preview.cpp, reaper.cpp, recovery.cpp; coordinator.cpp holds the shared
// state helpers.
#pragma once
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "coordinator/credentials.h"
#include "coordinator/handler.h"
#include "coordinator/job_store.h"
#include "coordinator/merge.h"
#include "coordinator/metrics.h"
#include "coordinator/snapshot.h"
#include "coordinator/result_store.h"

namespace mlt::farm {

struct CoordinatorOptions {
  std::string stateDir;
  double heartbeatSeconds = 1.0;      // told to workers
  double leaseTimeoutSeconds = 10.0;  // a lease not renewed for this long is queued again
  bool keepPartials = false;          // also write STATE/jobs/<id>/partials/task-NNNN.exr
  int maxAttempts = 3;
  double leaseWaitSeconds = 1.0;
  std::string sceneRoot;              // non-empty: SubmitJob may name a scene file under this directory
  SubmitQuotas quotas;
  double previewEverySeconds = 0;     // > 0: write STATE/jobs/<id>/preview.{exr,png} this often while running      // LeaseWork long-polls this long when there is nothing to lease                // a task that failed (report or lease expiry) this often fails its job
};

class Coordinator final : public ClientHandler, public WorkerHandler {
 public:
  explicit Coordinator(CoordinatorOptions options);  // opens/creates the state dir, reloads jobs
  ~Coordinator() override;
  void stop();                                        // stops background threads

  // ClientHandler
  JobStatus submit(SubmitRequest request) override;
  JobStatus get(const std::string& jobId) override;
  JobStatus waitForChange(const std::string& jobId, uint64_t afterVersion, std::chrono::milliseconds timeout) override;
  JobStatus cancel(const std::string& jobId) override;
  std::vector<JobStatus> list() override;
  std::string resultPath(const std::string& jobId, const std::string& format) override;
  void deleteJob(const std::string& jobId) override;
  SubmitQuotas quotas() const override { return opt_.quotas; }

  // For operators (coordinator/snapshot.cpp): every job and worker as of now, and the developed image of a
  // job's accepted tasks (the preview's develop step, as PNG bytes).
  FarmSnapshot snapshot();
  PreviewPng previewPng(const std::string& jobId);  // FarmError NotFound / FailedPrecondition
  // Event counters and histograms (Prometheus, coordinator/metrics.h); scraped only with --metrics-listen.
  CoordinatorMetrics& metrics() { return metrics_; }

  // WorkerHandler
  Registration registerWorker(const WorkerInfo& info) override;
  std::vector<Lease> lease(const std::string& workerId, int maxTasks) override;
  HeartbeatReply heartbeat(const std::string& workerId, const std::vector<std::string>& leaseIds) override;
  std::vector<BundleFile> scene(const std::string& sceneHash) override;
  JobPlan plan(const std::string& jobId) override;
  std::shared_ptr<const JobPlan> sharedPlan(const std::string& jobId) override;
  void admitUpload(const UploadAnnouncement& a) override;
  UploadReply upload(const std::string& workerId, const std::string& leaseId, const std::string& jobId,
                     uint32_t taskIndex, PartialResult result) override;
  void returnLeases(const std::string& workerId, const std::vector<std::string>& leaseIds) override;
  FailureReply reportFailure(const std::string& workerId, const std::string& leaseId, const std::string& jobId,
                             uint32_t taskIndex, const std::string& message) override;

 private:
  using Clock = std::chrono::steady_clock;
  enum class TaskState : uint8_t { Pending, Leased, Accepted };
  struct Job {
    JobRecord rec;
    JobStatus status;
    std::shared_ptr<const JobPlan> plan;
    std::vector<TaskRange> tasks;
    std::vector<TaskState> taskState;
    std::deque<uint32_t> pending;
    std::vector<uint32_t> attempts;           // failed attempts per task (reports + lease expiries)
    std::map<std::string, std::string> defines;  // scene parameters (Mitsuba -D)
    Clock::time_point renderStart;
    uint64_t workDoneAtStart = 0;  // accepted before this process started (for the ETA)
    uint32_t previewTasks = 0;     // tasks in the last preview
    uint64_t samplesAccepted = 0;  // pixel samples / mutations of the accepted tasks (metrics, web page)
    uint64_t samplesAtStart = 0;   // of those, accepted before renderStart (for the rate)
    ChainStats statsAccepted;      // acceptance of the accepted tasks' chains
    // The accepted results, summed in task order as they arrive: `merged` holds tasks [0, mergedTasks);
    // an accepted task beyond that waits in `waiting` until the tasks before it are in. Only while the
    // job runs (emptied once the image is written).
    PartialResult merged;
    uint32_t mergedTasks = 0;
    std::map<uint32_t, PartialResult> waiting;
    bool deleted = false;  // DeleteJob: files gone, invisible to clients; kept for threads still holding the id
    // Leases their worker gave back (ReturnLeases, a worker stopping): never resumed by liveLease, so that
    // a heartbeat or upload of that worker still in flight cannot take the task back after the return.
    std::set<std::string> returnedLeases;
  };
  struct LeaseRec {
    std::string workerId;
    int64_t job = 0;
    uint32_t task = 0;
    Clock::time_point deadline;
  };
  struct WorkerRec {
    WorkerInfo info;
    Clock::time_point lastSeen;
  };

  JobStatus submitChecked(SubmitRequest request);  // submit, before messages are cleaned of server paths
  bool sceneInUse(const std::string& hash) const;  // by a job or a submission; caller holds mu_
  void recover();                          // reload the state directory (recovery.cpp)
  bool finalImagesExist(int64_t id) const;  // image.exr and image.png of a DONE job (recovery.cpp)
  Job& findJob(const std::string& jobId);  // FarmError NotFound; caller holds mu_
  void touch(Job& job);                    // bump version, notify watchers; caller holds mu_
  void refreshProgress(Job& job);
  // Never throws: a state the database cannot record (disk full, read-only) is kept in memory and logged.
  void setState(Job& job, JobState s, const std::string& error = {});
  // One step of a background thread (planning, merging) for job `id`: whatever `step` throws fails that
  // job with the reason instead of ending the process. Caller does not hold mu_.
  void runGuarded(int64_t id, const char* role, const std::function<void()>& step);
  // Plan known: build tasks, mark the stored results accepted and (loadResults) sum them, queue the rest.
  void startRunning(Job& job, bool loadResults = true);
  void foldAccepted(Job& job, uint32_t task, PartialResult result);  // caller holds mu_
  // A leased task's attempt failed: requeue it, or fail the job when it is out of attempts. Returns true
  // if the job failed. Caller holds mu_.
  bool taskAttemptFailed(Job& job, uint32_t task, const std::string& reason);
  std::vector<Lease> leaseNow(const std::string& workerId, int maxTasks);  // caller holds mu_
  // A registered worker, or one registered before a restart of this state directory (its id checks out,
  // credentials.h: taken back). nullptr for an unknown or made-up id. Caller holds mu_.
  WorkerRec* knownWorker(const std::string& workerId);
  // The live lease `leaseId` of `workerId`: an entry of leases_ held by that worker, or a lease this state
  // directory issued to it whose task nobody holds now (it expired, or was issued before a restart), taken
  // back. nullptr with the reason in `why` otherwise (unknown, made up, another worker's, given away, the
  // job over). Caller holds mu_.
  LeaseRec* liveLease(const std::string& workerId, const std::string& leaseId, std::string& why);
  // Checks an upload's lease: throws FarmError FailedPrecondition unless `leaseId` is the live lease of
  // `workerId` on (job, taskIndex). Caller holds mu_.
  void requireLease(const Job& job, const std::string& workerId, const std::string& leaseId, uint32_t taskIndex);
  std::string sceneDir(const std::string& hash) const;
  std::string jobDir(int64_t id) const;
  void plannerLoop();
  void reaperLoop();
  void previewLoop();                                                   // coordinator/preview.cpp
  void writePreview(int64_t id, std::unique_lock<std::mutex>& lock);   // unlocks while merging
  void merge(int64_t id);
  void planOne(int64_t id);

  CoordinatorOptions opt_;
  CoordinatorMetrics metrics_;
  std::unique_ptr<JobStore> store_;     // jobs and plans (SQLite)
  std::unique_ptr<ResultStore> results_;  // accepted task results (files)
  std::unique_ptr<Credentials> creds_;    // worker and lease ids that check out (STATE/lease.key)
  std::mutex mu_;
  std::condition_variable changed_;     // status changes (watchers)
  std::condition_variable work_;        // planner: jobs to plan or merge
  std::map<int64_t, Job> jobs_;
  std::map<std::string, LeaseRec> leases_;
  std::map<std::string, WorkerRec> workers_;
  std::map<std::string, int> bundlesInSubmit_;  // scene hash -> submissions using its directory right now
  uint64_t nextLease_ = 1, nextWorker_ = 1;
  std::string instance_;                // random per process: ids never collide across restarts
  bool stopping_ = false;
  std::thread planner_, reaper_, preview_;
};

std::string formatJobId(int64_t id);
int64_t parseJobId(const std::string& jobId);  // FarmError NotFound for malformed ids

}  // namespace mlt::farm
