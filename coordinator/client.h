// A client of the coordinator's API (used by the `mltfarm submit|status|watch|cancel|fetch|jobs`
// subcommands, the embedded farm and the tests). Every call has a deadline; failures throw
// RpcError (proto/channel.h) carrying the gRPC status code and message.
#pragma once
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/farm/farm_types.h"
#include "proto/channel.h"
#include "proto/convert.h"
#include "proto/mltfarm.grpc.pb.h"


namespace mlt::farm {

class FarmClient {
 public:
  explicit FarmClient(ChannelOptions options);
  ~FarmClient();

  // Submits a scene as a bundle (read and hashed locally) or, with coordinatorPath = true, as a path the
  // coordinator reads itself.
  JobStatus submit(const std::string& sceneFile, const wire::SubmittedSettings& settings, int priority = 0,
                   const std::string& name = "", bool coordinatorPath = false);
  // Submit with an explicit bundle (tests: malformed scenes, missing files).
  JobStatus submitBundle(const std::vector<BundleFile>& files, const std::string& sceneFile,
                         const wire::SubmittedSettings& settings, int priority = 0, const std::string& name = "");
  JobStatus get(const std::string& jobId);
  JobStatus cancel(const std::string& jobId);
  std::vector<JobStatus> list();  // every job, fetched page by page
  // DeleteJob: removes a finished, failed or cancelled job and its files.
  void remove(const std::string& jobId);
  // Streams progress to `onStatus` until the job is terminal; returns the final status.
  JobStatus watch(const std::string& jobId, const std::function<void(const JobStatus&)>& onStatus,
                  std::chrono::seconds deadline = std::chrono::hours(24 * 7));
  // Writes the finished image ("exr" or "png") to `path`; returns the bytes received.
  uint64_t fetch(const std::string& jobId, const std::string& path, const std::string& format = "exr");
  // Standard health check (grpc.health.v1); true when SERVING.
  bool healthy(std::chrono::milliseconds deadline = std::chrono::milliseconds(2000));

  const ChannelOptions& options() const { return opt_; }
  std::shared_ptr<grpc::Channel> channel() const { return channel_; }

 private:
  ChannelOptions opt_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<mltfarm::v1::Coordinator::Stub> stub_;
};

// "RUNNING rendering 3/16 tasks  b=0.123  mutations 1.2M/4M  eta 12s"
std::string describeStatus(const JobStatus& s);

}  // namespace mlt::farm
