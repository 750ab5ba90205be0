// gRPC services of the coordinator (see service.h).
#include "coordinator/service.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <map>

#include "coordinator/storage_error.h"
#include "coordinator/auth.h"
#include "common/core/clip.h"
#include "coordinator/coordinator.h"  // formatJobId / parseJobId (ListJobs page tokens)
#include "proto/farm_convert.h"
#include "proto/sparse_film.h"
#include "proto/plan_pages.h"
#include "proto/mltfarm.grpc.pb.h"

namespace mlt::farm {
namespace {

using grpc::ServerContext;
using grpc::Status;
using grpc::StatusCode;

// The client's host as gRPC names the peer ("ipv4:127.0.0.1:5000" -> "ipv4:127.0.0.1"): one client for
// the jobs-per-client quota.
std::string peerHost(const std::string& peer) {
  const size_t colon = peer.rfind(':');
  return colon == std::string::npos || peer.rfind("unix:", 0) == 0 ? peer : peer.substr(0, colon);
}

// Runs `body` with auth and exception mapping.
template <class F>
Status guarded(ServerContext* ctx, const TokenCheck& token, const char* rpc, F&& body) {
  Status auth = token.check(*ctx);
  if (!auth.ok()) {
    spdlog::warn("rpc={} peer={} event=unauthenticated", rpc, ctx->peer());
    return auth;
  }
  try {
    return body();
  } catch (...) {
    Status s = statusFromException(std::current_exception());
    spdlog::log(s.error_code() == StatusCode::INTERNAL ? spdlog::level::err : spdlog::level::info,
                "rpc={} peer={} status={} message=\"{}\"", rpc, ctx->peer(), int(s.error_code()), s.error_message());
    return s;
  }
}

// Appends a chunk to its file; chunks of a file arrive in order. The bundle quotas hold while receiving.
void appendChunk(std::map<std::string, std::string>& files, uint64_t& total, const v1::FileChunk& c,
                 const SubmitQuotas& quota) {
  if (c.data().size() > wire::kMaxChunkBytes)
    throw wire::WireError("chunk.data", fmt::format("{} bytes exceeds the 1 MiB chunk limit", c.data().size()));
  if (!files.count(c.path()) && files.size() >= quota.maxBundleFiles)
    throw FarmError(FarmError::Code::ResourceExhausted,
                    fmt::format("bundle: more than {} files (--max-bundle-files)", quota.maxBundleFiles));
  if (total + c.data().size() > quota.maxBundleBytes)
    throw FarmError(FarmError::Code::ResourceExhausted,
                    fmt::format("bundle: more than {} bytes (--max-bundle-bytes)", quota.maxBundleBytes));
  std::string& f = files[c.path()];
  if (c.offset() != f.size())
    throw wire::WireError("chunk.offset", fmt::format("file '{}': offset {} but {} bytes received", clipForMessage(c.path()), c.offset(), f.size()));
  total += c.data().size();
  f += c.data();
}

class CoordinatorServiceImpl final : public v1::Coordinator::Service {
 public:
  CoordinatorServiceImpl(ClientHandler& h, const std::string& token) : h_(h), token_(token) {}

  Status SubmitJob(ServerContext* ctx, grpc::ServerReader<v1::SubmitJobRequest>* reader,
                   v1::SubmitJobResponse* resp) override {
    return guarded(ctx, token_, "SubmitJob", [&] {
      v1::SubmitJobRequest msg;
      if (!reader->Read(&msg) || !msg.has_header())
        throw wire::WireError("header", "the first message of SubmitJob must be the header");
      v1::SubmitHeader header = msg.header();
      wire::checkVersion(header.format_version(), "SubmitHeader");
      std::map<std::string, std::string> files;
      uint64_t total = 0;
      const SubmitQuotas quota = h_.quotas();
      while (reader->Read(&msg)) {
        if (!msg.has_chunk()) throw wire::WireError("chunk", "only file chunks may follow the header");
        appendChunk(files, total, msg.chunk(), quota);
      }
      std::vector<BundleFile> bundle;
      for (auto& [path, data] : files) bundle.push_back({path, std::move(data)});
      SubmitRequest request = fromProto(header, std::move(bundle));
      request.client = peerHost(ctx->peer());
      JobStatus st = h_.submit(std::move(request));
      *resp->mutable_status() = toProto(st);
      return Status::OK;
    });
  }

  Status GetJob(ServerContext* ctx, const v1::JobRef* req, v1::JobStatus* resp) override {
    return guarded(ctx, token_, "GetJob", [&] {
      wire::checkVersion(req->format_version(), "JobRef");
      *resp = toProto(h_.get(req->job_id()));
      return Status::OK;
    });
  }

  Status WatchJob(ServerContext* ctx, const v1::JobRef* req, grpc::ServerWriter<v1::JobStatus>* writer) override {
    return guarded(ctx, token_, "WatchJob", [&] {
      wire::checkVersion(req->format_version(), "JobRef");
      JobStatus st = h_.get(req->job_id());
      uint64_t sent = ~uint64_t(0);
      while (!ctx->IsCancelled()) {
        if (st.version != sent) {
          if (!writer->Write(toProto(st))) break;
          sent = st.version;
        }
        if (isTerminal(st.state)) break;
        st = h_.waitForChange(req->job_id(), st.version, std::chrono::milliseconds(500));
      }
      return Status::OK;
    });
  }

  Status CancelJob(ServerContext* ctx, const v1::JobRef* req, v1::JobStatus* resp) override {
    return guarded(ctx, token_, "CancelJob", [&] {
      wire::checkVersion(req->format_version(), "JobRef");
      *resp = toProto(h_.cancel(req->job_id()));
      return Status::OK;
    });
  }

  // Pages in job id order: at most page_size jobs (default 100, at most 1000) and about 1 MiB of them
  // (always at least one job), so a reply stays under the 4 MiB limit whatever the names hold.
  Status ListJobs(ServerContext* ctx, const v1::ListJobsRequest* req, v1::ListJobsResponse* resp) override {
    return guarded(ctx, token_, "ListJobs", [&] {
      wire::checkVersion(req->format_version(), "ListJobsRequest");
      const int64_t after = req->page_token().empty() ? 0 : parseJobId(req->page_token());
      const size_t pageSize = req->page_size() == 0 ? 100 : std::min<size_t>(req->page_size(), 1000);
      constexpr size_t kPageBytes = 1 << 20;
      size_t bytes = 0;
      std::string last;
      bool more = false;
      for (const JobStatus& s : h_.list()) {
        if (parseJobId(s.jobId) <= after) continue;
        v1::JobStatus p = toProto(s);
        if (resp->jobs_size() > 0 && (size_t(resp->jobs_size()) >= pageSize || bytes + p.ByteSizeLong() > kPageBytes)) {
          more = true;
          break;
        }
        bytes += p.ByteSizeLong();
        last = s.jobId;
        *resp->add_jobs() = std::move(p);
      }
      if (more) resp->set_next_page_token(last);
      return Status::OK;
    });
  }

  Status DeleteJob(ServerContext* ctx, const v1::JobRef* req, v1::DeleteJobResponse*) override {
    return guarded(ctx, token_, "DeleteJob", [&] {
      wire::checkVersion(req->format_version(), "JobRef");
      h_.deleteJob(req->job_id());
      return Status::OK;
    });
  }

  Status FetchResult(ServerContext* ctx, const v1::FetchResultRequest* req,
                     grpc::ServerWriter<v1::ResultChunk>* writer) override {
    return guarded(ctx, token_, "FetchResult", [&] {
      wire::checkVersion(req->format_version(), "FetchResultRequest");
      std::string path = h_.resultPath(req->job_id(), req->format().empty() ? "exr" : req->format());
      std::ifstream in(path, std::ios::binary);
      if (!in) throw FarmError(FarmError::Code::Internal, fmt::format("{}: cannot read result", path));
      in.seekg(0, std::ios::end);
      const uint64_t total = uint64_t(in.tellg());
      in.seekg(0);
      std::string buf(wire::kMaxChunkBytes, '\0');
      uint64_t offset = 0;
      do {
        in.read(buf.data(), std::streamsize(buf.size()));
        v1::ResultChunk c;
        c.set_offset(offset);
        c.set_total(total);
        c.set_data(buf.data(), size_t(in.gcount()));
        offset += uint64_t(in.gcount());
        if (!writer->Write(c)) break;
      } while (offset < total);
      return Status::OK;
    });
  }

 private:
  ClientHandler& h_;
  TokenCheck token_;
};

class WorkerServiceImpl final : public v1::WorkerService::Service {
 public:
  WorkerServiceImpl(WorkerHandler& h, const std::string& token, std::function<void(uint64_t, double)> onUpload)
      : h_(h), token_(token), onUpload_(std::move(onUpload)) {}

  Status Register(ServerContext* ctx, const v1::RegisterRequest* req, v1::RegisterResponse* resp) override {
    return guarded(ctx, token_, "Register", [&] {
      wire::checkVersion(req->format_version(), "RegisterRequest");
      if (req->threads() < 1 || req->threads() > 4096)
        throw wire::WireError("threads", fmt::format("{} is out of range [1, 4096]", req->threads()));
      Registration r = h_.registerWorker({req->hostname(), req->threads(), req->pid()});
      resp->set_worker_id(r.workerId);
      resp->set_heartbeat_interval_seconds(r.heartbeatSeconds);
      resp->set_lease_timeout_seconds(r.leaseTimeoutSeconds);
      return Status::OK;
    });
  }

  Status LeaseWork(ServerContext* ctx, const v1::LeaseRequest* req, v1::LeaseResponse* resp) override {
    return guarded(ctx, token_, "LeaseWork", [&] {
      wire::checkVersion(req->format_version(), "LeaseRequest");
      if (req->max_tasks() < 1 || req->max_tasks() > 4096)
        throw wire::WireError("max_tasks", fmt::format("{} is out of range [1, 4096]", req->max_tasks()));
      for (const Lease& l : h_.lease(req->worker_id(), req->max_tasks())) *resp->add_leases() = toProto(l);
      if (resp->leases().empty()) resp->set_retry_after_seconds(0.02);  // the handler already long-polled
      return Status::OK;
    });
  }

  Status Heartbeat(ServerContext* ctx, const v1::HeartbeatRequest* req, v1::HeartbeatResponse* resp) override {
    return guarded(ctx, token_, "Heartbeat", [&] {
      wire::checkVersion(req->format_version(), "HeartbeatRequest");
      HeartbeatReply r = h_.heartbeat(req->worker_id(), {req->lease_ids().begin(), req->lease_ids().end()});
      resp->set_unknown_worker(r.unknownWorker);
      for (auto& id : r.cancelledLeases) resp->add_cancelled_lease_ids(id);
      return Status::OK;
    });
  }

  Status FetchScene(ServerContext* ctx, const v1::FetchSceneRequest* req,
                    grpc::ServerWriter<v1::FileChunk>* writer) override {
    return guarded(ctx, token_, "FetchScene", [&] {
      wire::checkVersion(req->format_version(), "FetchSceneRequest");
      for (const BundleFile& f : h_.scene(req->scene_hash())) {
        uint64_t offset = 0;
        do {
          size_t n = std::min<uint64_t>(wire::kMaxChunkBytes, f.data.size() - offset);
          v1::FileChunk c;
          c.set_path(f.path);
          c.set_offset(offset);
          c.set_data(f.data.data() + offset, n);
          offset += n;
          c.set_last(offset == f.data.size());
          if (!writer->Write(c)) return Status(StatusCode::CANCELLED, "client went away");
        } while (offset < f.data.size());
      }
      return Status::OK;
    });
  }

  Status FetchPlan(ServerContext* ctx, const v1::FetchPlanRequest* req, v1::JobPlan* resp) override {
    return guarded(ctx, token_, "FetchPlan", [&] {
      wire::checkVersion(req->format_version(), "FetchPlanRequest");
      // A page of units (proto/plan_pages.h): a whole plan of many units exceeds the 4 MiB reply limit.
      try {
        *resp = wire::planPage(*h_.sharedPlan(req->job_id()), req->first_unit(), req->max_units());
      } catch (const wire::PlanPageRangeError& e) {
        return Status(StatusCode::OUT_OF_RANGE, e.what());
      }
      return Status::OK;
    });
  }

  Status UploadResult(ServerContext* ctx, grpc::ServerReader<v1::UploadResultRequest>* reader,
                      v1::UploadResultResponse* resp) override {
    return guarded(ctx, token_, "UploadResult", [&] {
      v1::UploadResultRequest msg;
      if (!reader->Read(&msg) || !msg.has_header())
        throw wire::WireError("header", "the first message of UploadResult must be the header");
      const auto t0 = std::chrono::steady_clock::now();
      const v1::UploadHeader header = msg.header();
      wire::checkVersion(header.format_version(), "UploadHeader");
      const v1::PartialHeader& ph = header.partial();
      if (ph.width() < 1 || ph.height() < 1 || ph.width() > 16384 || ph.height() > 16384)
        throw wire::WireError("partial.width", fmt::format("film {}x{} out of range", ph.width(), ph.height()));
      const std::vector<uint32_t> layerList = wire::headerLayers(ph);
      const size_t layers = layerList.size();
      if (layers > wire::kMaxSplatLayer + 1)
        throw wire::WireError("partial.splat_layers", fmt::format("{} layers", layers));
      if (!std::is_sorted(layerList.begin(), layerList.end()) || layerList.front() != 0)
        throw wire::WireError("partial.splat_layers", "must ascend from layer 0");
      // Who sends it and what it announces, before a byte of the film is reserved or read: only the holder
      // of the task's live lease, only a film of the job's size.
      h_.admitUpload({header.worker_id(), header.lease_id(), header.job_id(), header.task_index(), int(ph.width()),
                      int(ph.height()), layerList});
      const bool raw = ph.film_encoding() == v1::FILM_RAW;
      if (raw ? ph.film_bytes() != wire::filmByteSize(ph.width(), ph.height(), layers)
              : ph.film_bytes() > wire::maxZeroRunsBytes(ph.width(), ph.height(), layers))
        throw wire::WireError("partial.film_bytes", fmt::format("{} for a {}x{} film with {} splat layers", ph.film_bytes(),
                                                                ph.width(), ph.height(), layers));
      std::string film;
      film.reserve(std::min<uint64_t>(ph.film_bytes(), 64ull << 20));  // grows with what arrives beyond that
      while (reader->Read(&msg)) {
        if (!msg.has_film_chunk()) throw wire::WireError("film_chunk", "only film chunks may follow the header");
        if (msg.film_chunk().size() > wire::kMaxChunkBytes)
          throw wire::WireError("film_chunk", fmt::format("{} bytes exceeds the 1 MiB chunk limit", msg.film_chunk().size()));
        if (film.size() + msg.film_chunk().size() > ph.film_bytes())
          throw wire::WireError("film_chunk", "more film bytes than announced");
        film += msg.film_chunk();
      }
      PartialResult result = wire::fromProto(ph, film);
      UploadReply r = h_.upload(header.worker_id(), header.lease_id(), header.job_id(), header.task_index(), std::move(result));
      if (onUpload_)
        onUpload_(film.size(), std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      resp->set_accepted(r.accepted);
      resp->set_message(r.message);
      return Status::OK;
    });
  }

  Status ReportFailure(ServerContext* ctx, const v1::ReportFailureRequest* req, v1::ReportFailureResponse* resp) override {
    return guarded(ctx, token_, "ReportFailure", [&] {
      wire::checkVersion(req->format_version(), "ReportFailureRequest");
      if (req->message().size() > 64 * 1024)
        throw wire::WireError("message", fmt::format("{} bytes (at most 64 KiB)", req->message().size()));
      FailureReply r = h_.reportFailure(req->worker_id(), req->lease_id(), req->job_id(), req->task_index(), req->message());
      resp->set_job_failed(r.jobFailed);
      return Status::OK;
    });
  }

  Status ReturnLeases(ServerContext* ctx, const v1::ReturnLeaseRequest* req, v1::ReturnLeaseResponse*) override {
    return guarded(ctx, token_, "ReturnLeases", [&] {
      wire::checkVersion(req->format_version(), "ReturnLeaseRequest");
      h_.returnLeases(req->worker_id(), {req->lease_ids().begin(), req->lease_ids().end()});
      return Status::OK;
    });
  }

 private:
  WorkerHandler& h_;
  TokenCheck token_;
  std::function<void(uint64_t, double)> onUpload_;
};

}  // namespace

grpc::Status statusFromException(std::exception_ptr e) {
  constexpr size_t kMaxMessage = 4096;  // a backstop: messages echo client input only as a short prefix
  try {
    std::rethrow_exception(e);
  } catch (const FarmError& f) {
    StatusCode code = StatusCode::INTERNAL;
    switch (f.code()) {
      case FarmError::Code::InvalidArgument: code = StatusCode::INVALID_ARGUMENT; break;
      case FarmError::Code::NotFound: code = StatusCode::NOT_FOUND; break;
      case FarmError::Code::FailedPrecondition: code = StatusCode::FAILED_PRECONDITION; break;
      case FarmError::Code::AlreadyExists: code = StatusCode::ALREADY_EXISTS; break;
      case FarmError::Code::Unauthenticated: code = StatusCode::UNAUTHENTICATED; break;
      case FarmError::Code::Unavailable: code = StatusCode::UNAVAILABLE; break;
      case FarmError::Code::Internal: code = StatusCode::INTERNAL; break;
      case FarmError::Code::ResourceExhausted: code = StatusCode::RESOURCE_EXHAUSTED; break;
    }
    return Status(code, clipForMessage(f.what(), kMaxMessage));
  } catch (const wire::WireError& w) {
    return Status(StatusCode::INVALID_ARGUMENT, clipForMessage(w.what(), kMaxMessage));
  } catch (const std::filesystem::filesystem_error& x) {  // the state directory: full, read-only, failing
    const FarmError f = storageError(x.what(), x.code().value());
    return Status(f.code() == FarmError::Code::ResourceExhausted ? StatusCode::RESOURCE_EXHAUSTED
                                                                 : StatusCode::UNAVAILABLE,
                  clipForMessage(f.what(), kMaxMessage));
  } catch (const std::exception& x) {
    return Status(StatusCode::INTERNAL, clipForMessage(x.what(), kMaxMessage));
  } catch (...) {
    return Status(StatusCode::INTERNAL, "unknown error");
  }
}

RunningServer startServer(const ServerOptions& options, ClientHandler& clients, WorkerHandler& workers) {
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  RunningServer rs;
  rs.clientService = std::make_unique<CoordinatorServiceImpl>(clients, options.token);
  rs.workerService = std::make_unique<WorkerServiceImpl>(workers, options.token, options.onUpload);
  checkListenPolicy(options);
  std::shared_ptr<grpc::ServerCredentials> creds = serverCredentials(options);
  grpc::ServerBuilder builder;
  builder.AddListeningPort(options.listen, creds, &rs.port);
  builder.RegisterService(rs.clientService.get());
  builder.RegisterService(rs.workerService.get());
  rs.server = builder.BuildAndStart();
  if (!rs.server || rs.port == 0) throw std::runtime_error(fmt::format("cannot listen on {}", options.listen));
  rs.server->GetHealthCheckService()->SetServingStatus(true);
  return rs;
}

}  // namespace mlt::farm
