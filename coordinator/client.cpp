// Coordinator API client (see client.h).
#include "coordinator/client.h"

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include <condition_variable>
#include <mutex>

#include <filesystem>
#include <fmt/format.h>
#include <fstream>

#include "common/farm/bundle.h"
#include "proto/farm_convert.h"
#include "proto/convert.h"

namespace mlt::farm {
namespace {

constexpr auto kShortDeadline = std::chrono::seconds(30);
constexpr auto kSubmitDeadline = std::chrono::minutes(10);  // includes scene loading on the coordinator

[[noreturn]] void fail(const grpc::Status& s, const char* rpc) { throw RpcError(s.error_code(), rpc, s.error_message()); }

}  // namespace

FarmClient::FarmClient(ChannelOptions options)
    : opt_(std::move(options)), channel_(makeChannel(opt_)), stub_(v1::Coordinator::NewStub(channel_)) {}
FarmClient::~FarmClient() = default;

JobStatus FarmClient::submit(const std::string& sceneFile, const wire::SubmittedSettings& settings, int priority,
                             const std::string& name, bool coordinatorPath) {
  if (!coordinatorPath) {
    SceneBundle b = collectBundle(sceneFile, settings.defines);
    return submitBundle(b.files, b.sceneFile, settings, priority, name.empty() ? sceneFile : name);
  }
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_, kSubmitDeadline);
  v1::SubmitJobResponse resp;
  auto writer = stub_->SubmitJob(&ctx, &resp);
  v1::SubmitJobRequest req;
  auto* h = req.mutable_header();
  h->set_format_version(wire::kFormatVersion);
  *h->mutable_settings() = wire::toProto(settings);
  h->set_priority(priority);
  h->set_name(name.empty() ? sceneFile : name);
  h->set_coordinator_path(std::filesystem::absolute(sceneFile).string());
  writer->Write(req);
  writer->WritesDone();
  grpc::Status s = writer->Finish();
  if (!s.ok()) fail(s, "SubmitJob");
  return fromProto(resp.status());
}

JobStatus FarmClient::submitBundle(const std::vector<BundleFile>& files, const std::string& sceneFile,
                                   const wire::SubmittedSettings& settings, int priority, const std::string& name) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_, kSubmitDeadline);
  v1::SubmitJobResponse resp;
  auto writer = stub_->SubmitJob(&ctx, &resp);
  v1::SubmitJobRequest req;
  auto* h = req.mutable_header();
  h->set_format_version(wire::kFormatVersion);
  *h->mutable_settings() = wire::toProto(settings);
  h->set_priority(priority);
  h->set_name(name);
  h->set_bundle_scene_file(sceneFile);
  h->set_bundle_hash(bundleHash(files));
  bool ok = writer->Write(req);
  for (const BundleFile& f : files) {
    uint64_t offset = 0;
    do {
      size_t n = std::min<uint64_t>(wire::kMaxChunkBytes, f.data.size() - offset);
      v1::SubmitJobRequest c;
      c.mutable_chunk()->set_path(f.path);
      c.mutable_chunk()->set_offset(offset);
      c.mutable_chunk()->set_data(f.data.data() + offset, n);
      offset += n;
      c.mutable_chunk()->set_last(offset == f.data.size());
      ok = ok && writer->Write(c);
    } while (ok && offset < f.data.size());
  }
  writer->WritesDone();
  grpc::Status s = writer->Finish();
  if (!s.ok()) fail(s, "SubmitJob");
  return fromProto(resp.status());
}

namespace {
// A unary call that takes a job id (GetJob, CancelJob: a job status; DeleteJob).
template <typename Response = v1::JobStatus, typename Call>
Response jobCall(const ChannelOptions& opt, const std::string& jobId, const char* rpc, Call call) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt, kShortDeadline);
  v1::JobRef ref;
  ref.set_format_version(wire::kFormatVersion);
  ref.set_job_id(jobId);
  Response resp;
  grpc::Status s = call(&ctx, ref, &resp);
  if (!s.ok()) fail(s, rpc);
  return resp;
}
}  // namespace

JobStatus FarmClient::get(const std::string& jobId) {
  return fromProto(jobCall(opt_, jobId, "GetJob", [&](grpc::ClientContext* c, const v1::JobRef& r, v1::JobStatus* o) {
    return stub_->GetJob(c, r, o);
  }));
}

JobStatus FarmClient::cancel(const std::string& jobId) {
  return fromProto(jobCall(opt_, jobId, "CancelJob", [&](grpc::ClientContext* c, const v1::JobRef& r, v1::JobStatus* o) {
    return stub_->CancelJob(c, r, o);
  }));
}

std::vector<JobStatus> FarmClient::list() {
  std::vector<JobStatus> out;
  std::string token;
  do {  // page by page (each reply stays under the message limit)
    grpc::ClientContext ctx;
    prepareContext(ctx, opt_, kShortDeadline);
    v1::ListJobsRequest req;
    req.set_format_version(wire::kFormatVersion);
    req.set_page_token(token);
    v1::ListJobsResponse resp;
    grpc::Status s = stub_->ListJobs(&ctx, req, &resp);
    if (!s.ok()) fail(s, "ListJobs");
    for (const auto& j : resp.jobs()) out.push_back(fromProto(j));
    if (!resp.next_page_token().empty() && resp.next_page_token() == token)
      throw RpcError(grpc::StatusCode::INTERNAL, "ListJobs", "the page token did not advance");
    token = resp.next_page_token();
  } while (!token.empty());
  return out;
}

void FarmClient::remove(const std::string& jobId) {
  jobCall<v1::DeleteJobResponse>(opt_, jobId, "DeleteJob",
                                 [&](grpc::ClientContext* c, const v1::JobRef& r, v1::DeleteJobResponse* o) {
                                   return stub_->DeleteJob(c, r, o);
                                 });
}

JobStatus FarmClient::watch(const std::string& jobId, const std::function<void(const JobStatus&)>& onStatus,
                            std::chrono::seconds deadline) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_, deadline);
  v1::JobRef ref;
  ref.set_format_version(wire::kFormatVersion);
  ref.set_job_id(jobId);
  auto reader = stub_->WatchJob(&ctx, ref);
  v1::JobStatus msg;
  JobStatus last;
  bool any = false;
  while (reader->Read(&msg)) {
    last = fromProto(msg);
    any = true;
    if (onStatus) onStatus(last);
  }
  grpc::Status s = reader->Finish();
  if (!s.ok()) fail(s, "WatchJob");
  if (!any) throw RpcError(grpc::UNKNOWN, "WatchJob", "stream ended without a status");
  return last;
}

uint64_t FarmClient::fetch(const std::string& jobId, const std::string& path, const std::string& format) {
  grpc::ClientContext ctx;
  prepareContext(ctx, opt_, std::chrono::minutes(30));
  v1::FetchResultRequest req;
  req.set_format_version(wire::kFormatVersion);
  req.set_job_id(jobId);
  req.set_format(format);
  auto reader = stub_->FetchResult(&ctx, req);
  const std::string tmp = path + ".part";
  uint64_t received = 0, total = 0;
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write", tmp));
    v1::ResultChunk c;
    while (reader->Read(&c)) {
      if (c.offset() != received) throw std::runtime_error("FetchResult: chunks out of order");
      out.write(c.data().data(), std::streamsize(c.data().size()));
      received += c.data().size();
      total = c.total();
    }
    grpc::Status s = reader->Finish();
    if (!s.ok()) {
      std::filesystem::remove(tmp);
      fail(s, "FetchResult");
    }
  }
  if (received != total)
    throw std::runtime_error(fmt::format("FetchResult: received {} of {} bytes", received, total));
  std::filesystem::rename(tmp, path);
  return received;
}

bool FarmClient::healthy(std::chrono::milliseconds deadline) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + deadline);
  // grpc.health.v1.Health/Check with an empty HealthCheckRequest (service "" = the whole server):
  // the generic stub avoids generating health.proto ourselves.
  grpc::GenericStub generic(channel_);
  grpc::Slice emptySlice(std::string{});
  grpc::ByteBuffer request(&emptySlice, 1);  // the empty message
  grpc::ByteBuffer response;
  grpc::Status status;
  std::mutex m;
  std::condition_variable cv;
  bool done = false;
  generic.UnaryCall(&ctx, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                    [&](grpc::Status s) {
                      std::lock_guard lock(m);
                      status = s;
                      done = true;
                      cv.notify_all();
                    });
  std::unique_lock lock(m);
  cv.wait(lock, [&] { return done; });
  if (!status.ok()) return false;
  // HealthCheckResponse { ServingStatus status = 1; } SERVING = 1 -> bytes 08 01.
  std::vector<grpc::Slice> slices;
  response.Dump(&slices);
  std::string bytes;
  for (auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  return bytes == std::string("\x08\x01", 2);
}

std::string describeStatus(const JobStatus& s) {
  std::string out = fmt::format("{} {} [{}]", s.jobId, jobStateName(s.state), s.phase);
  if (s.b > 0) out += fmt::format("  b={:.6g}±{:.2g}", s.b, s.bStdErr);
  if (s.workTotal > 0) out += fmt::format("  work {}/{} ({:.0f}%)", s.workDone, s.workTotal, 100.0 * double(s.workDone) / double(s.workTotal));
  if (s.unitsTotal > 0) out += fmt::format("  units {}/{}", s.unitsDone, s.unitsTotal);
  if (s.failedAttempts > 0) out += fmt::format("  failed attempts {}", s.failedAttempts);
  if (s.etaSeconds >= 0 && s.state == JobState::Running) out += fmt::format("  eta {:.1f}s", s.etaSeconds);
  if (!s.error.empty()) out += "  error: " + s.error;
  return out;
}

}  // namespace mlt::farm
