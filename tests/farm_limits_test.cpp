// Limits and clean-up (issue 13): ListJobs pages (two jobs with 3 MiB names do not break `jobs`),
// quotas on bundles, files, jobs per client and job names (a rejected bundle leaves nothing behind),
// DeleteJob removes a job's files, and error messages echo client input only as a short prefix.
#include <gtest/gtest.h>

#include <sqlite3.h>

#include <filesystem>

#include "coordinator/coordinator.h"
#include "coordinator/job_store.h"
#include "coordinator/service.h"
#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

const char* kScene = R"(<scene version="3.0.0">
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film></sensor>
  <shape type="obj"><string name="filename" value="tri.obj"/>
    <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter></shape>
</scene>
)";
const char* kObj = "v -1 -1 3\nv 1 -1 3\nv 0 1 3\nf 1 2 3\n";

wire::SubmittedSettings tiny() {
  wire::SubmittedSettings s = tinySettings("pt");
  s.settings.width = s.settings.height = 16;
  return s;
}

// A coordinator in this process behind a real gRPC server on loopback.
struct InProcessServer {
  TempDir dir;
  std::unique_ptr<Coordinator> coordinator;
  RunningServer server;
  explicit InProcessServer(SubmitQuotas quotas = {}) {
    CoordinatorOptions o;
    o.stateDir = dir / "state";
    o.quotas = quotas;
    coordinator = std::make_unique<Coordinator>(o);
    ServerOptions so;
    so.listen = "127.0.0.1:0";
    server = startServer(so, *coordinator, *coordinator);
  }
  ~InProcessServer() {
    coordinator->stop();
    server.server->Shutdown();
  }
  FarmClient client() const { return FarmClient({"127.0.0.1:" + std::to_string(server.port), "", ""}); }
  std::string stateDir() const { return dir / "state"; }
  // Scene bundles stored (directories under STATE/scenes, temporary ones included).
  size_t storedBundles() const {
    size_t n = 0;
    for (const auto& e : fs::directory_iterator(stateDir() + "/scenes")) n += e.is_directory();
    return n;
  }
};

template <class F>
RpcError rpcErrorOf(F&& f) {
  try {
    f();
  } catch (const RpcError& e) {
    return e;
  }
  ADD_FAILURE() << "no error";
  return RpcError(grpc::StatusCode::OK, "", "");
}

TEST(FarmLimits, ListJobsPagesSoHugeNamesDoNotBreakTheListing) {
  SubmitQuotas q;
  q.maxJobNameBytes = 4u << 20;  // names this long exist (e.g. from before the quota)
  InProcessServer farm(q);
  auto c = farm.client();
  const std::string huge1(3 << 20, 'a'), huge2(3 << 20, 'b');
  c.submitBundle({{"scene.xml", kScene}, {"tri.obj", kObj}}, "scene.xml", tiny(), 0, huge1);
  c.submitBundle({{"scene.xml", kScene}, {"tri.obj", kObj}}, "scene.xml", tiny(), 0, huge2);
  c.submitBundle({{"scene.xml", kScene}, {"tri.obj", kObj}}, "scene.xml", tiny(), 0, "small");
  const std::vector<JobStatus> jobs = c.list();  // 6 MiB of names: more than one 4 MiB reply could hold
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[0].name, huge1);
  EXPECT_EQ(jobs[1].name, huge2);
  EXPECT_EQ(jobs[2].name, "small");
  EXPECT_EQ(jobs[2].jobId, "job-3");
}

TEST(FarmLimits, QuotasRefuseBigBundlesManyFilesLongNamesAndBusyClients) {
  SubmitQuotas q;
  q.maxBundleBytes = 4096;
  q.maxBundleFiles = 2;
  q.maxJobNameBytes = 16;
  q.maxJobsPerClient = 1;
  InProcessServer farm(q);
  auto c = farm.client();
  const std::vector<BundleFile> good{{"scene.xml", kScene}, {"tri.obj", kObj}};
  RpcError e = rpcErrorOf([&] {
    c.submitBundle({{"scene.xml", kScene}, {"tri.obj", kObj}, {"extra.txt", "x"}}, "scene.xml", tiny());
  });
  EXPECT_EQ(e.code(), grpc::RESOURCE_EXHAUSTED) << e.message();
  EXPECT_NE(e.message().find("--max-bundle-files"), std::string::npos) << e.message();
  e = rpcErrorOf([&] { c.submitBundle({{"scene.xml", kScene}, {"tri.obj", std::string(8192, ' ') + kObj}}, "scene.xml", tiny()); });
  EXPECT_EQ(e.code(), grpc::RESOURCE_EXHAUSTED) << e.message();
  EXPECT_NE(e.message().find("--max-bundle-bytes"), std::string::npos) << e.message();
  e = rpcErrorOf([&] { c.submitBundle(good, "scene.xml", tiny(), 0, std::string(17, 'n')); });
  EXPECT_EQ(e.code(), grpc::INVALID_ARGUMENT) << e.message();
  EXPECT_NE(e.message().find("name: 17 bytes exceeds the limit of 16"), std::string::npos) << e.message();
  // One unfinished job per client: the second waits until the first is cancelled.
  const JobStatus first = c.submitBundle(good, "scene.xml", tiny(), 0, "first");
  e = rpcErrorOf([&] { c.submitBundle(good, "scene.xml", tiny(), 0, "second"); });
  EXPECT_EQ(e.code(), grpc::RESOURCE_EXHAUSTED) << e.message();
  EXPECT_NE(e.message().find("--max-jobs-per-client"), std::string::npos) << e.message();
  c.cancel(first.jobId);
  EXPECT_NO_THROW(c.submitBundle(good, "scene.xml", tiny(), 0, "second"));
}

// The quota counts the jobs stored with their client: a restarted coordinator still refuses a client at
// its limit (the count used to live in memory only and started again from zero), and serves another one.
TEST(FarmLimits, JobsPerClientQuotaSurvivesARestart) {
  TempDir dir;
  SubmitQuotas q;
  q.maxJobsPerClient = 2;
  auto start = [&] {
    CoordinatorOptions o;
    o.stateDir = dir / "state";
    o.quotas = q;
    return std::make_unique<Coordinator>(o);
  };
  auto request = [](const std::string& client) {
    SubmitRequest r;
    const wire::SubmittedSettings s = tiny();
    r.settings = s.settings;
    r.hasSize = r.hasMaxDepth = r.hasSpp = true;
    r.bundle = {{"scene.xml", kScene}, {"tri.obj", kObj}};
    r.bundleSceneFile = "scene.xml";
    r.client = client;
    return r;
  };
  auto refused = [&](Coordinator& c, const std::string& client) {
    try {
      c.submit(request(client));
      ADD_FAILURE() << client << ": accepted past its quota";
    } catch (const FarmError& e) {
      EXPECT_EQ(int(e.code()), int(FarmError::Code::ResourceExhausted)) << e.what();
      EXPECT_NE(std::string(e.what()).find("2 unfinished jobs"), std::string::npos) << e.what();
    }
  };
  const std::string busy = "ipv4:10.0.0.1", other = "ipv4:10.0.0.2";
  auto coordinator = start();  // no workers: the jobs stay unfinished
  coordinator->submit(request(busy));
  coordinator->submit(request(busy));
  refused(*coordinator, busy);
  coordinator->stop();
  coordinator.reset();
  coordinator = start();  // the same state directory
  refused(*coordinator, busy);
  EXPECT_EQ(coordinator->submit(request(other)).jobId, "job-3");
  refused(*coordinator, busy);
  coordinator->stop();
}

// A state directory written before jobs carried their client opens: its jobs have none, new ones do.
TEST(FarmLimits, AnOldJobTableWithoutAClientColumnOpens) {
  TempDir dir;
  const std::string db = dir / "farm.db";
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw,
                         "CREATE TABLE jobs(id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT, priority INTEGER,"
                         " state INTEGER, settings BLOB, scene_hash TEXT, scene_file TEXT, plan BLOB, tasks INTEGER,"
                         " error TEXT, submitted_at REAL);"
                         "INSERT INTO jobs(name, priority, state, tasks, submitted_at) VALUES('old', 0, 0, 0, 1.0);",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(raw);
  {
    JobStore store(db);
    JobRecord r;
    r.name = "new";
    r.client = "ipv4:10.0.0.1";
    EXPECT_EQ(store.insertJob(r), 2);
  }
  JobStore reopened(db);  // migrated once: opening again changes nothing
  const std::vector<JobRecord> jobs = reopened.loadJobs();
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs[0].name, "old");
  EXPECT_EQ(jobs[0].client, "");
  EXPECT_EQ(jobs[1].client, "ipv4:10.0.0.1");
}

TEST(FarmLimits, ARejectedBundleIsDeleted) {
  InProcessServer farm;
  auto c = farm.client();
  // The scene references a mesh the bundle lacks: refused after the bundle was stored to load it.
  const RpcError e = rpcErrorOf([&] { c.submitBundle({{"scene.xml", kScene}}, "scene.xml", tiny()); });
  EXPECT_EQ(e.code(), grpc::INVALID_ARGUMENT) << e.message();
  EXPECT_EQ(farm.storedBundles(), 0u);
  // A bundle a job uses stays; a rejected submission of the same files (bad -D) leaves it alone.
  const std::vector<BundleFile> good{{"scene.xml", kScene}, {"tri.obj", kObj}};
  c.submitBundle(good, "scene.xml", tiny());
  wire::SubmittedSettings bad = tiny();  // refused by the work limit, after the bundle is stored
  bad.settings.width = bad.settings.height = 16384;
  bad.settings.spp = 1 << 20;
  EXPECT_ANY_THROW(c.submitBundle(good, "scene.xml", bad));
  EXPECT_EQ(farm.storedBundles(), 1u);
}

TEST(FarmLimits, ErrorMessagesEchoOnlyAShortPrefixOfClientInput) {
  InProcessServer farm;
  auto c = farm.client();
  RpcError e = rpcErrorOf([&] { c.get("job-" + std::string(1 << 20, '7')); });
  EXPECT_EQ(e.code(), grpc::NOT_FOUND);
  EXPECT_LT(e.message().size(), 200u) << e.message().substr(0, 300);
  // An 8 MiB attribute value in the scene.
  const std::string scene = std::string("<scene version=\"3.0.0\">\n<shape type=\"") + std::string(8 << 20, 'x') + "\"/>\n</scene>\n";
  e = rpcErrorOf([&] { c.submitBundle({{"scene.xml", scene}}, "scene.xml", tiny()); });
  EXPECT_EQ(e.code(), grpc::INVALID_ARGUMENT);
  EXPECT_LT(e.message().size(), 1000u) << e.message().substr(0, 1200);
  EXPECT_NE(e.message().find("scene.xml:2:"), std::string::npos) << e.message().substr(0, 1200);
  EXPECT_EQ(e.message().find(farm.stateDir()), std::string::npos) << e.message().substr(0, 1200);
}

// Real processes: a job runs to DONE, is deleted with `mltfarm delete`, and its record, images and scene
// bundle are gone, also after a restart; a running job must be cancelled first.
TEST(FarmLimits, DeleteJobRemovesTheJobAndItsFiles) {
  Farm farm;
  farm.startCoordinator();
  farm.startWorker(1);
  auto c = farm.client();
  const JobStatus done = c.submitBundle({{"scene.xml", kScene}, {"tri.obj", kObj}}, "scene.xml", tiny());
  ASSERT_EQ(farm.waitDone(done.jobId).state, JobState::Done);
  const std::string jobDir = farm.stateDir + "/jobs/" + done.jobId, sceneDir = farm.stateDir + "/scenes/" + done.sceneHash;
  ASSERT_TRUE(fs::exists(jobDir + "/image.exr"));
  ASSERT_TRUE(fs::exists(sceneDir));
  ChildProcess cli({toolsDir() + "/mltfarm", "delete", done.jobId, "--coordinator", farm.coordinator->address},
                   farm.dir / "delete.log", false);
  ASSERT_EQ(cli.wait(std::chrono::seconds(60)), std::optional<int>(0)) << readFile(farm.dir / "delete.log");
  EXPECT_FALSE(fs::exists(jobDir));
  EXPECT_FALSE(fs::exists(sceneDir));
  EXPECT_EQ(rpcErrorOf([&] { c.get(done.jobId); }).code(), grpc::NOT_FOUND);
  EXPECT_EQ(rpcErrorOf([&] { c.remove(done.jobId); }).code(), grpc::NOT_FOUND);
  EXPECT_TRUE(c.list().empty());
  // A job that has not ended (no worker left to run it): cancel it first.
  farm.workers.front()->terminate(std::chrono::seconds(10));
  const JobStatus running = c.submitBundle({{"scene.xml", kScene}, {"tri.obj", kObj}}, "scene.xml", tiny());
  EXPECT_EQ(rpcErrorOf([&] { c.remove(running.jobId); }).code(), grpc::FAILED_PRECONDITION);
  c.cancel(running.jobId);
  c.remove(running.jobId);
  // Gone for good: a restarted coordinator does not bring them back.
  farm.coordinator->process.terminate(std::chrono::seconds(10));
  farm.startCoordinator();
  EXPECT_TRUE(farm.client().list().empty());
  EXPECT_EQ(rpcErrorOf([&] { farm.client().get(done.jobId); }).code(), grpc::NOT_FOUND);
}

}  // namespace
}  // namespace mlt::farm::test
