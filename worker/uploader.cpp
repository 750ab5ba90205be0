// Bulk transfers of the worker (see uploader.h).
#include "worker/uploader.h"

#include <fmt/format.h>
#include <map>

#include "common/farm/bundle.h"
#include "proto/convert.h"
#include "proto/plan_pages.h"
#include "proto/sparse_film.h"

namespace mlt::farm {

UploadReply uploadPartial(v1::WorkerService::Stub& stub, const ChannelOptions& o, const UploadTarget& target,
                          const PartialResult& result, size_t* chunks, uint64_t* filmBytes) {
  // Zero runs left out: most of a task's film is zero words (proto/sparse_film.h), and every byte sent is
  // copied several times on both sides.
  const std::string film = wire::encodeFilmZeroRuns(result.film);
  grpc::ClientContext ctx;
  // A generous deadline that grows with the film: 60 s + 1 s per MiB.
  prepareContext(ctx, o, std::chrono::milliseconds(60'000 + film.size() / 1024));
  v1::UploadResultResponse resp;
  auto writer = stub.UploadResult(&ctx, &resp);
  v1::UploadResultRequest req;
  auto* h = req.mutable_header();
  h->set_format_version(wire::kFormatVersion);
  h->set_worker_id(target.workerId);
  h->set_lease_id(target.leaseId);
  h->set_job_id(target.jobId);
  h->set_task_index(target.taskIndex);
  *h->mutable_partial() = wire::partialHeader(result);
  h->mutable_partial()->set_film_encoding(v1::FILM_ZERO_RUNS);
  h->mutable_partial()->set_film_bytes(film.size());
  bool ok = writer->Write(req);
  size_t sent = 0;
  for (size_t offset = 0; ok && offset < film.size(); offset += wire::kMaxChunkBytes) {
    v1::UploadResultRequest c;
    c.set_film_chunk(film.data() + offset, std::min(wire::kMaxChunkBytes, film.size() - offset));
    ok = writer->Write(c);
    ++sent;
  }
  writer->WritesDone();
  grpc::Status s = writer->Finish();
  if (!s.ok()) throw RpcError(s.error_code(), "UploadResult", s.error_message());
  if (chunks) *chunks = sent;
  if (filmBytes) *filmBytes = film.size();
  return {resp.accepted(), resp.message()};
}

std::vector<BundleFile> fetchScene(v1::WorkerService::Stub& stub, const ChannelOptions& o,
                                   const std::string& sceneHash) {
  grpc::ClientContext ctx;
  prepareContext(ctx, o, std::chrono::minutes(10));
  v1::FetchSceneRequest req;
  req.set_format_version(wire::kFormatVersion);
  req.set_scene_hash(sceneHash);
  auto reader = stub.FetchScene(&ctx, req);
  std::map<std::string, std::string> files;
  v1::FileChunk c;
  while (reader->Read(&c)) {
    std::string& f = files[c.path()];
    if (c.offset() != f.size()) throw std::runtime_error("FetchScene: chunks out of order");
    f += c.data();
  }
  grpc::Status s = reader->Finish();
  if (!s.ok()) throw RpcError(s.error_code(), "FetchScene", s.error_message());
  std::vector<BundleFile> out;
  for (auto& [path, data] : files) {
    validateBundlePath(path);
    out.push_back({path, std::move(data)});
  }
  if (bundleHash(out) != sceneHash)
    throw std::runtime_error(fmt::format("FetchScene: bundle content does not hash to {}", sceneHash));
  return out;
}

JobPlan fetchPlan(v1::WorkerService::Stub& stub, const ChannelOptions& o, const std::string& jobId,
                  uint64_t* bytes) {
  // Page by page (the server's default page): a plan of many units exceeds the 4 MiB reply limit.
  return wire::assemblePlanPages(
      [&](uint32_t firstUnit) {
        grpc::ClientContext ctx;
        prepareContext(ctx, o, std::chrono::seconds(60));
        v1::FetchPlanRequest req;
        req.set_format_version(wire::kFormatVersion);
        req.set_job_id(jobId);
        req.set_first_unit(firstUnit);
        v1::JobPlan page;
        grpc::Status s = stub.FetchPlan(&ctx, req, &page);
        if (!s.ok()) throw RpcError(s.error_code(), "FetchPlan", s.error_message());
        return page;
      },
      bytes);
}

}  // namespace mlt::farm
