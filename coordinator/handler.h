// The coordinator's behaviour as two interfaces speaking domain types. The gRPC services
// (coordinator/service.h) do transport only and call these; tests can drive a fake.
#pragma once
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "common/methods/registry.h"
#include "common/farm/farm_types.h"

namespace mlt::farm {

// Limits on what one submission may hold (the coordinator's --max-* options).
struct SubmitQuotas {
  uint64_t maxBundleBytes = 1ull << 30;  // the uploaded (or collected) files together
  uint32_t maxBundleFiles = 10000;
  uint32_t maxJobsPerClient = 1000;      // unfinished jobs (queued, planning, running, merging) per client
  uint32_t maxJobNameBytes = 1024;
};

class ClientHandler {
 public:
  virtual ~ClientHandler() = default;
  virtual JobStatus submit(SubmitRequest request) = 0;                 // FarmError InvalidArgument, ...
  virtual JobStatus get(const std::string& jobId) = 0;                 // FarmError NotFound
  // Blocks until the job's status version exceeds `afterVersion`, or `timeout` passes; returns the status.
  virtual JobStatus waitForChange(const std::string& jobId, uint64_t afterVersion,
                                  std::chrono::milliseconds timeout) = 0;
  virtual JobStatus cancel(const std::string& jobId) = 0;              // FailedPrecondition if terminal
  virtual std::vector<JobStatus> list() = 0;
  // Path of the finished image ("exr" or "png"); FailedPrecondition until the job is done.
  virtual std::string resultPath(const std::string& jobId, const std::string& format) = 0;
  // Removes a finished, failed or cancelled job and its files (FailedPrecondition while it runs).
  virtual void deleteJob(const std::string& /*jobId*/) {
    throw FarmError(FarmError::Code::FailedPrecondition, "DeleteJob: not supported by this handler");
  }
  virtual SubmitQuotas quotas() const { return {}; }  // the transport enforces the bundle limits while receiving
};

// What an upload announces in its header, checked before a byte of its film is read or reserved.
struct UploadAnnouncement {
  std::string workerId, leaseId, jobId;
  uint32_t taskIndex = 0;
  int width = 0, height = 0;
  std::vector<uint32_t> splatLayers;  // ascending, layer 0 first
};

class WorkerHandler {
 public:
  virtual ~WorkerHandler() = default;
  virtual Registration registerWorker(const WorkerInfo& info) = 0;
  virtual std::vector<Lease> lease(const std::string& workerId, int maxTasks) = 0;
  virtual HeartbeatReply heartbeat(const std::string& workerId, const std::vector<std::string>& leaseIds) = 0;
  // The bundle's files (NotFound for an unknown hash).
  virtual std::vector<BundleFile> scene(const std::string& sceneHash) = 0;
  virtual JobPlan plan(const std::string& jobId) = 0;
  // The same plan, shared rather than copied (FetchPlan cuts a page from it per call). The default copies.
  virtual std::shared_ptr<const JobPlan> sharedPlan(const std::string& jobId) {
    return std::make_shared<const JobPlan>(plan(jobId));
  }
  // Throws FarmError unless the announced upload may be read: the worker holds the live lease of that
  // task and the film has the job's size. The default admits everything (transport tests' fakes).
  virtual void admitUpload(const UploadAnnouncement&) {}
  // Accepts a task's result once: only from the worker holding its live lease, only a film the task can
  // hold (sizes, units, sample count, finite and quantized values); a task already accepted is dropped as
  // a duplicate (accepted = false).
  virtual UploadReply upload(const std::string& workerId, const std::string& leaseId, const std::string& jobId,
                             uint32_t taskIndex, PartialResult result) = 0;
  virtual void returnLeases(const std::string& workerId, const std::vector<std::string>& leaseIds) = 0;
  // A leased task failed on the worker: requeue it, or fail the job once the task is out of attempts.
  virtual FailureReply reportFailure(const std::string& workerId, const std::string& leaseId,
                                     const std::string& jobId, uint32_t taskIndex, const std::string& message) = 0;
};

}  // namespace mlt::farm
