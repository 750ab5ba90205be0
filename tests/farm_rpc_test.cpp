// The coordinator's RPC surface under bad input (real processes on loopback): every bad request gets the
// right status code and a message naming the problem, and the coordinator keeps serving the other jobs.
// Plus the transport of a 1920x1080 partial film in chunks under gRPC's default 4 MiB limit (in-process
// server with a fake handler), and the health check.
#include <gtest/gtest.h>

#include <condition_variable>

#include "coordinator/service.h"
#include "proto/convert.h"
#include "proto/sparse_film.h"
#include "tests/farm/farm_harness.h"
#include "worker/uploader.h"

namespace mlt::farm::test {
namespace {

const char* kObjScene = R"(<scene version="3.0.0">
  <sensor type="perspective">
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
  </sensor>
  <shape type="obj"><string name="filename" value="meshes/tri.obj"/>
    <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter></shape>
</scene>
)";
const char* kObj = "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n";

TEST(FarmRpc, BadInputGetsTheRightStatusAndOtherJobsKeepRunning) {
  Farm farm;
  farm.token = "s3cret";
  farm.startCoordinator();
  farm.startWorker(1);
  auto c = farm.client();
  EXPECT_TRUE(c.healthy());

  // A good job that must survive everything below.
  JobStatus good = c.submit(cornellBox(), tinySettings("pssmlt"));

  // A bundle with a referenced file works (and proves the bundle carries it).
  JobStatus withObj = c.submitBundle({{"scene.xml", kObjScene}, {"meshes/tri.obj", kObj}}, "scene.xml",
                                     tinySettings("pt"));
  EXPECT_EQ(withObj.width, 32);

  // Malformed scene: INVALID_ARGUMENT carrying the loader's message (file name).
  expectRpcError([&] { c.submitBundle({{"broken.xml", "<scene version=\"3.0.0\"><shape"}}, "broken.xml", tinySettings("pt")); },
                 grpc::INVALID_ARGUMENT, "broken.xml", "malformed scene");
  // Missing referenced file.
  expectRpcError([&] { c.submitBundle({{"scene.xml", kObjScene}}, "scene.xml", tinySettings("pt")); },
                 grpc::INVALID_ARGUMENT, "tri.obj", "missing referenced file");
  // Scene file not in the bundle; path escaping the bundle.
  expectRpcError([&] { c.submitBundle({{"scene.xml", kObjScene}}, "other.xml", tinySettings("pt")); },
                 grpc::INVALID_ARGUMENT, "bundle_scene_file", "scene file not in bundle");
  expectRpcError([&] { c.submitBundle({{"../evil.xml", kObjScene}}, "../evil.xml", tinySettings("pt")); },
                 grpc::INVALID_ARGUMENT, "..", "path escaping the bundle");
  // Absurd parameters.
  auto bad = [&](auto mutate, const std::string& field, const char* what) {
    wire::SubmittedSettings s = tinySettings("pssmlt");
    mutate(s);
    expectRpcError([&] { c.submit(cornellBox(), s); }, grpc::INVALID_ARGUMENT, field, what);
  };
  bad([](auto& s) { s.settings.width = s.settings.height = 0; }, "settings.width", "0x0 film");
  bad([](auto& s) { s.settings.mutationsPerPixel = 1e9; }, "settings.chains.mutations_per_pixel", "1e9 mutations per pixel");
  bad([](auto& s) { s.settings.mutationsPerPixel = -4; }, "settings.chains.mutations_per_pixel", "negative mutations");
  bad([](auto& s) { s.settings.spp = -1; }, "settings.chains.direct.spp", "negative spp");
  bad([](auto& s) { s.settings.chains = -3; }, "settings.chains", "negative chains");
  bad([](auto& s) { s.settings.width = -32; }, "settings.width", "negative width");
  bad([](auto& s) { s.settings.integrator.maxDepth = -7; }, "settings.max_depth", "negative depth");
  bad([](auto& s) { s.settings.largeStepProb = 1.5f; }, "settings.chains.large_step_prob", "probability > 1");
  bad([](auto& s) { s.settings.method = "metropolis"; }, "settings.method", "unknown method");
  bad([](auto& s) { s.settings.params["no-such-param"] = "1"; }, "no-such-param", "a parameter pssmlt does not have");
  // mmlt runs chains per path length: a max depth of 0 (no path at all) is refused at submission, not when
  // planning.
  bad([](auto& s) {
    s.settings.method = "mmlt";
    s.settings.integrator.maxDepth = 0;
    s.hasMaxDepth = true;
  }, "max depth >= 1 or -1", "mmlt with max depth 0");
  // Unknown job ids.
  expectRpcError([&] { c.get("job-999"); }, grpc::NOT_FOUND, "job-999", "unknown job");
  expectRpcError([&] { c.get("nonsense"); }, grpc::NOT_FOUND, "nonsense", "malformed job id");
  expectRpcError([&] { c.fetch("job-999", farm.dir / "x.exr"); }, grpc::NOT_FOUND, "job-999", "fetch unknown job");
  // Cancel twice: the second is FAILED_PRECONDITION.
  JobStatus victim = c.submit(cornellBox(), tinySettings("bdpt"), -5);  // low priority: still queued/running
  EXPECT_EQ(c.cancel(victim.jobId).state, JobState::Cancelled);
  expectRpcError([&] { c.cancel(victim.jobId); }, grpc::FAILED_PRECONDITION, "already CANCELLED", "cancel twice");
  expectRpcError([&] { c.fetch(victim.jobId, farm.dir / "x.exr"); }, grpc::FAILED_PRECONDITION, "CANCELLED",
                 "fetch cancelled job");
  // Wrong or missing token: UNAUTHENTICATED on every service.
  expectRpcError([&] { farm.client("wrong").get(good.jobId); }, grpc::UNAUTHENTICATED, "token", "wrong token");
  expectRpcError([&] { farm.client("").list(); }, grpc::UNAUTHENTICATED, "token", "no token");
  expectRpcError([&] { farm.client("wrong").submit(cornellBox(), tinySettings("pt")); }, grpc::UNAUTHENTICATED,
                 "token", "submit with wrong token");
  {
    auto stub = v1::WorkerService::NewStub(farm.client("wrong").channel());
    grpc::ClientContext ctx;
    prepareContext(ctx, {farm.coordinator->address, "wrong", ""}, std::chrono::seconds(10));
    v1::RegisterRequest req;
    req.set_format_version(wire::kFormatVersion);
    req.set_threads(1);
    v1::RegisterResponse resp;
    EXPECT_EQ(stub->Register(&ctx, req, &resp).error_code(), grpc::UNAUTHENTICATED);
  }
  // A peer speaking another format version.
  {
    auto stub = v1::Coordinator::NewStub(c.channel());
    grpc::ClientContext ctx;
    prepareContext(ctx, c.options(), std::chrono::seconds(10));
    v1::JobRef ref;
    ref.set_format_version(wire::kFormatVersion + 1);
    ref.set_job_id(good.jobId);
    v1::JobStatus resp;
    grpc::Status s = stub->GetJob(&ctx, ref, &resp);
    EXPECT_EQ(s.error_code(), grpc::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find("format_version"), std::string::npos) << s.error_message();
  }

  // Through all that, the good jobs finished.
  EXPECT_EQ(farm.waitDone(good.jobId).state, JobState::Done);
  EXPECT_EQ(farm.waitDone(withObj.jobId).state, JobState::Done);
  c.fetch(good.jobId, farm.dir / "good.exr");
  EXPECT_GT(fs::file_size(farm.dir / "good.exr"), 1000u);
  EXPECT_EQ(c.list().size(), 3u);  // good, withObj, victim: rejected submissions left no job behind
}

// A fake worker handler that only records the upload.
class RecordingHandler final : public WorkerHandler, public ClientHandler {
 public:
  PartialResult received;
  uint32_t task = 0;
  Registration registerWorker(const WorkerInfo&) override { return {"w", 1, 10}; }
  std::vector<Lease> lease(const std::string&, int) override { return {}; }
  HeartbeatReply heartbeat(const std::string&, const std::vector<std::string>&) override { return {}; }
  std::vector<BundleFile> scene(const std::string&) override { return {}; }
  JobPlan plan(const std::string&) override { return {}; }
  UploadReply upload(const std::string&, const std::string&, const std::string&, uint32_t taskIndex,
                     PartialResult result) override {
    received = std::move(result);
    task = taskIndex;
    return {true, "ok"};
  }
  void returnLeases(const std::string&, const std::vector<std::string>&) override {}
  FailureReply reportFailure(const std::string&, const std::string&, const std::string&, uint32_t,
                             const std::string&) override {
    return {};
  }
  JobStatus submit(SubmitRequest) override { throw FarmError(FarmError::Code::Internal, "fake"); }
  JobStatus get(const std::string&) override { throw FarmError(FarmError::Code::NotFound, "fake"); }
  JobStatus waitForChange(const std::string&, uint64_t, std::chrono::milliseconds) override { return {}; }
  JobStatus cancel(const std::string&) override { return {}; }
  std::vector<JobStatus> list() override { return {}; }
  std::string resultPath(const std::string&, const std::string&) override { return {}; }
};

TEST(FarmRpc, FullHdFilmTravelsInChunksUnderTheDefaultMessageLimit) {
  RecordingHandler handler;
  ServerOptions so;
  so.listen = "127.0.0.1:0";
  RunningServer server = startServer(so, handler, handler);  // default 4 MiB receive limit
  ChannelOptions co{"127.0.0.1:" + std::to_string(server.port), "", ""};
  auto stub = v1::WorkerService::NewStub(makeChannel(co));

  PartialResult r;
  r.film = Film(1920, 1080);
  for (size_t i = 0; i < r.film.pixelCount(); ++i) {  // distinct, non-trivial bit patterns everywhere
    r.film.pixelSums()[i] = {double(i) * 1e-3, 1.0 / double(i + 1), -double(i)};
    r.film.pixelCounts()[i] = double(i % 97);
    r.film.splatSums()[i] = {std::sqrt(double(i)), double(i) * 3.25, 0.1 * double(i % 13)};
    r.film.splatLayer(4)[i] = {1.0 / double(i + 3), double(i % 7), -0.5 * double(i)};  // a chain length's layer
  }
  r.samples = 123456789;
  r.units = {3, 4, 5};
  r.stats.proposedPerKind = {42, 7};
  r.stats.largeStepSums = {{}, {}, {}, {42, 1.0 / 3.0, 0.125}};
  // Uploads leave the film's zero runs out (proto/sparse_film.h); this film has almost none.
  const size_t bytes = wire::encodeFilmZeroRuns(r.film).size();
  ASSERT_GT(bytes, size_t(4) << 20) << "the film must exceed the 4 MiB message limit for this test to mean anything";
  size_t chunks = 0;
  UploadReply reply = uploadPartial(*stub, co, {"w", "l", "job-1", 7}, r, &chunks);
  EXPECT_TRUE(reply.accepted);
  EXPECT_EQ(chunks, (bytes + wire::kMaxChunkBytes - 1) / wire::kMaxChunkBytes);
  EXPECT_EQ(handler.task, 7u);
  ASSERT_EQ(handler.received.film.width(), 1920);
  ASSERT_EQ(handler.received.film.height(), 1080);
  EXPECT_EQ(wire::encodeFilm(handler.received.film), wire::encodeFilm(r.film)) << "film bytes changed in transit";
  EXPECT_EQ(handler.received.samples, r.samples);
  EXPECT_EQ(handler.received.units, r.units);
  EXPECT_EQ(handler.received.stats.proposedPerKind, r.stats.proposedPerKind);
  EXPECT_TRUE(handler.received.film.hasSplatLayer(4));
  EXPECT_EQ(handler.received.stats.largeStepSums, r.stats.largeStepSums);

  // A single message carrying the whole film is refused by the default limit: chunking is what works.
  grpc::ClientContext ctx;
  prepareContext(ctx, co, std::chrono::seconds(30));
  v1::UploadResultResponse resp;
  auto writer = stub->UploadResult(&ctx, &resp);
  v1::UploadResultRequest header;
  header.mutable_header()->set_format_version(wire::kFormatVersion);
  *header.mutable_header()->mutable_partial() = wire::partialHeader(r);
  writer->Write(header);
  v1::UploadResultRequest whole;
  whole.set_film_chunk(wire::encodeFilm(r.film));
  writer->Write(whole);
  writer->WritesDone();
  EXPECT_EQ(writer->Finish().error_code(), grpc::RESOURCE_EXHAUSTED);
  server.server->Shutdown();
}

}  // namespace
}  // namespace mlt::farm::test
