// The worker's RPCs (see coordinator_client.h): domain values in, protobuf messages built here only.
#include "worker/coordinator_client.h"

#include "proto/convert.h"
#include "proto/farm_convert.h"
#include "proto/mltfarm.grpc.pb.h"

namespace mlt::farm {
namespace {

void check(const grpc::Status& s, const char* rpc) {
  if (!s.ok()) throw RpcError(s.error_code(), rpc, s.error_message());
}

}  // namespace

struct CoordinatorClient::Stub {
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::WorkerService::Stub> service;
};

CoordinatorClient::CoordinatorClient(ChannelOptions options) : opt_(std::move(options)), stub_(std::make_unique<Stub>()) {
  stub_->channel = makeChannel(opt_);
  stub_->service = v1::WorkerService::NewStub(stub_->channel);
}

CoordinatorClient::~CoordinatorClient() = default;

Registration CoordinatorClient::registerWorker(const WorkerInfo& info) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_, std::chrono::seconds(10));
  v1::RegisterRequest req;
  req.set_format_version(wire::kFormatVersion);
  req.set_hostname(info.hostname);
  req.set_threads(info.threads);
  req.set_pid(info.pid);
  v1::RegisterResponse resp;
  check(stub_->service->Register(&ctx, req, &resp), "Register");
  Registration r;
  r.workerId = resp.worker_id();
  r.heartbeatSeconds = resp.heartbeat_interval_seconds();
  r.leaseTimeoutSeconds = resp.lease_timeout_seconds();
  return r;
}

LeaseBatch CoordinatorClient::lease(const std::string& workerId, int maxTasks) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_, std::chrono::seconds(10));
  v1::LeaseRequest req;
  req.set_format_version(wire::kFormatVersion);
  req.set_worker_id(workerId);
  req.set_max_tasks(maxTasks);
  v1::LeaseResponse resp;
  check(stub_->service->LeaseWork(&ctx, req, &resp), "LeaseWork");
  LeaseBatch b;
  for (const auto& l : resp.leases()) b.leases.push_back(fromProto(l));
  b.retryAfterSeconds = resp.retry_after_seconds();
  return b;
}

HeartbeatReply CoordinatorClient::heartbeat(const std::string& workerId, const std::vector<std::string>& leaseIds,
                                            std::chrono::milliseconds deadline) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_, deadline);
  v1::HeartbeatRequest req;
  req.set_format_version(wire::kFormatVersion);
  req.set_worker_id(workerId);
  for (const auto& l : leaseIds) req.add_lease_ids(l);
  v1::HeartbeatResponse resp;
  check(stub_->service->Heartbeat(&ctx, req, &resp), "Heartbeat");
  HeartbeatReply r;
  r.unknownWorker = resp.unknown_worker();
  r.cancelledLeases.assign(resp.cancelled_lease_ids().begin(), resp.cancelled_lease_ids().end());
  return r;
}

std::vector<BundleFile> CoordinatorClient::scene(const std::string& sceneHash) {
  return fetchScene(*stub_->service, opt_, sceneHash);
}

JobPlan CoordinatorClient::plan(const std::string& jobId, uint64_t* bytes) {
  return fetchPlan(*stub_->service, opt_, jobId, bytes);
}

UploadReply CoordinatorClient::upload(const UploadTarget& target, const PartialResult& result, uint64_t* filmBytes) {
  return uploadPartial(*stub_->service, opt_, target, result, nullptr, filmBytes);
}

FailureReply CoordinatorClient::reportFailure(const std::string& workerId, const Lease& lease,
                                              const std::string& message) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_, std::chrono::seconds(10));
  v1::ReportFailureRequest req;
  req.set_format_version(wire::kFormatVersion);
  req.set_worker_id(workerId);
  req.set_lease_id(lease.leaseId);
  req.set_job_id(lease.jobId);
  req.set_task_index(lease.taskIndex);
  req.set_message(message.substr(0, 60 * 1024));
  v1::ReportFailureResponse resp;
  check(stub_->service->ReportFailure(&ctx, req, &resp), "ReportFailure");
  return {resp.job_failed()};
}

void CoordinatorClient::returnLeases(const std::string& workerId, const std::vector<std::string>& leaseIds) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_, std::chrono::seconds(5));
  v1::ReturnLeaseRequest req;
  req.set_format_version(wire::kFormatVersion);
  req.set_worker_id(workerId);
  for (const auto& l : leaseIds) req.add_lease_ids(l);
  v1::ReturnLeaseResponse resp;
  check(stub_->service->ReturnLeases(&ctx, req, &resp), "ReturnLeases");
}

}  // namespace mlt::farm
