// The worker's side of the WorkerService, speaking domain types (common/farm/farm_types.h) like the
// coordinator's WorkerHandler (coordinator/handler.h) does on the other side: the worker loop never
// sees a protobuf message. Every call has a deadline; a failed call throws RpcError (proto/channel.h)
// with the gRPC status code, which tells the loop whether to back off and retry (isTransient) or not.
#pragma once
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "common/farm/farm_types.h"
#include "common/job/job_types.h"
#include "proto/channel.h"
#include "worker/uploader.h"

namespace mlt::farm {

// What LeaseWork returns: leases, or none and how long to wait before asking again.
struct LeaseBatch {
  std::vector<Lease> leases;
  double retryAfterSeconds = 0;
};

class CoordinatorClient {
 public:
  explicit CoordinatorClient(ChannelOptions options);
  ~CoordinatorClient();

  Registration registerWorker(const WorkerInfo& info);
  // Long-polls on the coordinator while it has nothing to lease. FAILED_PRECONDITION: register again.
  LeaseBatch lease(const std::string& workerId, int maxTasks);
  HeartbeatReply heartbeat(const std::string& workerId, const std::vector<std::string>& leaseIds,
                           std::chrono::milliseconds deadline);
  // The bundle's files, checked against the hash.
  std::vector<BundleFile> scene(const std::string& sceneHash);
  JobPlan plan(const std::string& jobId, uint64_t* bytes = nullptr);  // bytes: received on the wire
  // Streams the partial film in chunks of at most 1 MiB (worker/uploader.h); filmBytes: sent on the wire.
  UploadReply upload(const UploadTarget& target, const PartialResult& result, uint64_t* filmBytes = nullptr);
  FailureReply reportFailure(const std::string& workerId, const Lease& lease, const std::string& message);
  void returnLeases(const std::string& workerId, const std::vector<std::string>& leaseIds);

  const ChannelOptions& options() const { return opt_; }

 private:
  struct Stub;  // the generated stub stays out of this header
  ChannelOptions opt_;
  std::unique_ptr<Stub> stub_;
};

}  // namespace mlt::farm
