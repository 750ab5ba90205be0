// The coordinator's web page and JSON API (--http-listen): the token is required (401 without it), the
// JSON shapes, the live preview (the develop step's PNG of the accepted tasks, bit for bit), cancel and
// fetch, and the page's static files.
#include <httplib.h>

#include <nlohmann/json.hpp>

#include "common/io/png_io.h"
#include "coordinator/http_server.h"
#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

using nlohmann::json;

struct Http {
  int port = 0;
  std::string token;
  httplib::Result get(const std::string& path, const std::string& tok = "\x01") {
    httplib::Client cli("127.0.0.1", port);
    httplib::Headers h;
    const std::string t = tok == "\x01" ? token : tok;
    if (!t.empty()) h.emplace("Authorization", "Bearer " + t);
    return cli.Get(path.c_str(), h);
  }
  httplib::Result post(const std::string& path) {
    httplib::Client cli("127.0.0.1", port);
    return cli.Post(path.c_str(), httplib::Headers{{"Authorization", "Bearer " + token}}, "", "text/plain");
  }
  json getJson(const std::string& path) {
    auto r = get(path);
    EXPECT_TRUE(r && r->status == 200) << path << ": " << (r ? r->body : "no answer");
    return r ? json::parse(r->body) : json();
  }
};

Http startWithHttp(Farm& farm) {
  farm.token = "s3cret-token";
  farm.startCoordinator({"--http-listen", "127.0.0.1:0", "--preview-every", "0"});
  auto line = farm.coordinator->process.readLine(std::chrono::seconds(10));
  EXPECT_TRUE(line && line->rfind("http on 127.0.0.1:", 0) == 0) << line.value_or("EOF");
  return {line ? std::stoi(line->substr(line->rfind(':') + 1)) : 0, farm.token};
}

std::string pngOf(const JobPlan& plan, const PartialResult& merged, const std::string& path) {
  writePng(path, plan.settings.width, plan.settings.height, developImage(plan, merged));
  return readFile(path);
}

TEST(FarmHttp, TokenRequiredForTheApiNotForThePage) {
  Farm farm;
  Http http = startWithHttp(farm);
  for (const char* path : {"/api/jobs", "/api/workers", "/api/jobs/job-1", "/api/jobs/job-1/preview.png"}) {
    auto none = http.get(path, "");
    ASSERT_TRUE(none);
    EXPECT_EQ(none->status, 401) << path;
    EXPECT_EQ(none->get_header_value("WWW-Authenticate"), "Bearer");
    EXPECT_TRUE(json::parse(none->body).contains("error"));
    auto wrong = http.get(path, "s3cret-tokem");
    EXPECT_EQ(wrong->status, 401) << path;
  }
  httplib::Client cli("127.0.0.1", http.port);
  EXPECT_EQ(cli.Post("/api/jobs/job-1/cancel", "", "text/plain")->status, 401);
  EXPECT_EQ(http.getJson("/api/jobs"), json::parse(R"({"jobs": []})"));
  // The page itself holds no data: served without the token.
  auto index = http.get("/", "");
  ASSERT_TRUE(index);
  EXPECT_EQ(index->status, 200);
  EXPECT_EQ(index->get_header_value("Content-Type"), "text/html; charset=utf-8");
  EXPECT_NE(index->body.find("<table id=\"jobs\">"), std::string::npos);
  EXPECT_NE(index->body.find("name=\"viewport\""), std::string::npos);  // readable on a phone
  for (const char* path : {"/job.html", "/app.js", "/style.css"}) EXPECT_EQ(http.get(path, "")->status, 200) << path;
  EXPECT_EQ(http.get("/nothing-here", "")->status, 404);
  EXPECT_EQ(http.get("/healthz", "")->body, "ok\n");
  EXPECT_EQ(http.get("/api/jobs/job-99")->status, 404);
  EXPECT_EQ(http.get("/api/jobs/nonsense")->status, 404);
}

TEST(FarmHttp, JobJsonLivePreviewCancelAndFetch) {
  Farm farm;
  Http http = startWithHttp(farm);
  // One slow single-thread worker: tasks are leased one at a time in order (one unit each here).
  farm.startWorker(1, {"--debug-task-delay-ms", "150"});
  auto c = farm.client();
  wire::SubmittedSettings s = tinySettings("pt");
  s.settings.spp = 16;
  JobStatus a = c.submit(cornellBox(), s);
  JobStatus b = c.submit(cornellBox(), tinySettings("pssmlt"), -1);  // behind a: not leased while a renders

  // Before any task is accepted there is no preview.
  json j0 = http.getJson("/api/jobs/" + a.jobId);
  if (j0["tasks_done"] == 0) EXPECT_EQ(http.get("/api/jobs/" + a.jobId + "/preview.png")->status, 409);

  farm.waitFor(a.jobId, [](const JobStatus& st) { return st.tasksDone >= 2; });
  auto pv = http.get("/api/jobs/" + a.jobId + "/preview.png");
  ASSERT_TRUE(pv);
  ASSERT_EQ(pv->status, 200) << pv->body;
  EXPECT_EQ(pv->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(pv->get_header_value("X-Preview-Final"), "0");
  const int k = std::stoi(pv->get_header_value("X-Preview-Tasks"));
  ASSERT_GE(k, 2);
  ASSERT_LT(k, 16) << "finished before the preview was fetched";

  // The list and the job's detail.
  json list = http.getJson("/api/jobs");
  ASSERT_EQ(list["jobs"].size(), 2u);
  EXPECT_EQ(list["jobs"][0]["id"], a.jobId);
  EXPECT_EQ(list["jobs"][1]["id"], b.jobId);
  json d = http.getJson("/api/jobs/" + a.jobId);
  for (const char* key : {"id", "name", "state", "phase", "method", "priority", "width", "height", "progress", "tasks_done",
                          "tasks_total", "tasks_leased", "tasks_queued", "eta_seconds", "elapsed_seconds", "b", "b_stderr",
                          "b_relative_stderr", "bootstrap_seconds", "samples", "samples_per_second", "failed_attempts",
                          "error", "submitted_at", "acceptance", "workers"})
    EXPECT_TRUE(d.contains(key)) << key;
  EXPECT_EQ(d["state"], "RUNNING");
  EXPECT_EQ(d["method"], "pt");
  EXPECT_EQ(d["tasks_total"], 16);
  EXPECT_GE(d["tasks_done"].get<int>(), k);
  EXPECT_GT(d["progress"].get<double>(), 0);
  EXPECT_LT(d["progress"].get<double>(), 1);
  EXPECT_TRUE(d["acceptance"].is_array());
  ASSERT_TRUE(d["workers"].is_array());
  json workers = http.getJson("/api/workers");
  ASSERT_EQ(workers["workers"].size(), 1u);
  for (const char* key : {"id", "host", "threads", "pid", "seconds_since_seen", "tasks"})
    EXPECT_TRUE(workers["workers"][0].contains(key)) << key;
  EXPECT_EQ(workers["workers"][0]["threads"], 1);

  // The preview is the develop step's image of the first k tasks (one unit each), byte for byte.
  const LocalUnits local = runUnitsLocally(cornellBox(), s, k);
  ASSERT_EQ(local.plan.units.size(), 16u);
  EXPECT_EQ(pv->body, pngOf(local.plan, local.merged, farm.dir / "expected.png")) << "preview of " << k << " tasks";

  // Cancel the second job from the API; again is a conflict.
  auto cancelled = http.post("/api/jobs/" + b.jobId + "/cancel");
  ASSERT_TRUE(cancelled);
  EXPECT_EQ(cancelled->status, 200) << cancelled->body;
  EXPECT_EQ(json::parse(cancelled->body)["state"], "CANCELLED");
  EXPECT_EQ(c.get(b.jobId).state, JobState::Cancelled);
  EXPECT_EQ(http.post("/api/jobs/" + b.jobId + "/cancel")->status, 409);
  EXPECT_EQ(http.get("/api/jobs/" + b.jobId + "/result.png")->status, 409);

  // Done: the preview is the final image, the same bytes as the fetched result.
  ASSERT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  auto fin = http.get("/api/jobs/" + a.jobId + "/preview.png");
  EXPECT_EQ(fin->get_header_value("X-Preview-Final"), "1");
  EXPECT_EQ(fin->get_header_value("X-Preview-Tasks"), "16");
  auto png = http.get("/api/jobs/" + a.jobId + "/result.png");
  ASSERT_EQ(png->status, 200);
  EXPECT_EQ(png->get_header_value("Content-Disposition"), "attachment; filename=\"" + a.jobId + ".png\"");
  c.fetch(a.jobId, farm.dir / "result.png", "png");
  EXPECT_EQ(png->body, readFile(farm.dir / "result.png"));
  EXPECT_EQ(fin->body, png->body);
  auto exr = http.get("/api/jobs/" + a.jobId + "/result.exr");
  c.fetch(a.jobId, farm.dir / "result.exr", "exr");
  EXPECT_EQ(exr->body, readFile(farm.dir / "result.exr"));
  json done = http.getJson("/api/jobs/" + a.jobId);
  EXPECT_EQ(done["state"], "DONE");
  EXPECT_EQ(done["progress"], 1.0);
  EXPECT_EQ(done["eta_seconds"], 0.0);
}

TEST(FarmHttp, NonLoopbackAddressNeedsAToken) {
  expectCoordinatorRefuses({"--http-listen", "0.0.0.0:0"}, "a non-loopback address needs a token");
  EXPECT_TRUE(isLoopbackHost("127.0.0.1:80"));
  EXPECT_TRUE(isLoopbackHost("[::1]:80"));
  EXPECT_TRUE(isLoopbackHost("localhost:0"));
  EXPECT_FALSE(isLoopbackHost("0.0.0.0:80"));
  EXPECT_FALSE(isLoopbackHost("10.1.2.3:80"));
}

}  // namespace
}  // namespace mlt::farm::test
