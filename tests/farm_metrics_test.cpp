// Prometheus metrics (--metrics-listen): /metrics scraped during a render and after it, on the coordinator
// and on a worker; the counters move with the work and the per-job gauges carry the job's own numbers.
// Also: health turns NOT_SERVING on SIGTERM before the coordinator drains (--shutdown-grace).
#include <httplib.h>

#include <cmath>
#include <regex>
#include <set>

#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

// The value of the first series named `name` whose labels contain every `labels` entry ("k=\"v\"");
// NaN when there is none.
double metric(const std::string& text, const std::string& name, const std::vector<std::string>& labels = {}) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const size_t end = line.find_first_of("{ ");
    if (end == std::string::npos || line.substr(0, end) != name) continue;
    bool all = true;
    for (const std::string& l : labels) all = all && line.find(l) != std::string::npos;
    if (all) return std::stod(line.substr(line.rfind(' ') + 1));
  }
  return std::nan("");
}

std::string scrape(int port) {
  httplib::Client cli("127.0.0.1", port);
  auto res = cli.Get("/metrics");
  EXPECT_TRUE(res) << "no answer from 127.0.0.1:" << port;
  if (!res) return {};
  EXPECT_EQ(res->status, 200);
  return res->body;
}

// Scrapes until `done(text)` (the last task's counters are updated right after its reply, which can be
// after the job is DONE), at most ~10 s; returns the last scrape.
template <class Pred>
std::string scrapeUntil(int port, Pred done) {
  std::string text;
  for (int i = 0; i < 200; ++i) {
    text = scrape(port);
    if (done(text)) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return text;
}

int portFromLine(const std::optional<std::string>& line, const std::string& prefix) {
  EXPECT_TRUE(line && line->rfind(prefix, 0) == 0) << "expected '" << prefix << "...', got " << line.value_or("EOF");
  if (!line || line->rfind(prefix, 0) != 0) return 0;
  return std::stoi(line->substr(line->rfind(':') + 1));
}

// The worker logs "event=metrics_listening address=HOST:PORT" once it serves.
int workerMetricsPort(const std::string& log) {
  for (int i = 0; i < 600; ++i) {
    std::smatch m;
    const std::string text = readFile(log);
    if (std::regex_search(text, m, std::regex("event=metrics_listening address=[^ ]*:([0-9]+)\n"))) return std::stoi(m[1]);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ADD_FAILURE() << "the worker did not log its metrics port: " << log;
  return 0;
}

TEST(FarmMetrics, CountersMoveDuringARenderAndGaugesCarryTheJob) {
  Farm farm;
  farm.startCoordinator({"--metrics-listen", "127.0.0.1:0"});
  const int port = portFromLine(farm.coordinator->process.readLine(std::chrono::seconds(10)), "metrics on 127.0.0.1:");
  ASSERT_GT(port, 0);
  const std::string idle = scrape(port);
  EXPECT_EQ(metric(idle, "mltfarm_tasks_accepted_total"), 0);
  EXPECT_EQ(metric(idle, "mltfarm_jobs", {"state=\"RUNNING\""}), 0);
  EXPECT_NE(idle.find("# TYPE mltfarm_upload_duration_seconds histogram"), std::string::npos);

  // One slow single-thread worker: tasks arrive one by one, so a scrape lands mid-render.
  farm.startWorker(1, {"--debug-task-delay-ms", "150", "--metrics-listen", "127.0.0.1:0"});
  const int workerPort = workerMetricsPort(farm.dir / "worker-0.log");
  auto c = farm.client();
  JobStatus a = c.submit(cornellBox(), tinySettings("pssmlt"));
  JobStatus mid = farm.waitFor(a.jobId, [](const JobStatus& s) { return s.tasksDone >= 1; });
  const std::string during = scrape(port);
  ASSERT_EQ(mid.state, JobState::Running) << "finished before the scrape";
  ASSERT_GE(mid.tasksTotal, 3u);
  const std::vector<std::string> job{"job=\"" + a.jobId + "\""};
  EXPECT_EQ(metric(during, "mltfarm_jobs", {"state=\"RUNNING\""}), 1);
  EXPECT_EQ(metric(during, "mltfarm_workers_connected"), 1);
  EXPECT_GE(metric(during, "mltfarm_tasks_accepted_total"), 1);
  EXPECT_LT(metric(during, "mltfarm_tasks_accepted_total"), mid.tasksTotal);
  EXPECT_GE(metric(during, "mltfarm_tasks_leased_total"), metric(during, "mltfarm_tasks_accepted_total"));
  EXPECT_GT(metric(during, "mltfarm_upload_bytes_total"), 0);
  EXPECT_GE(metric(during, "mltfarm_upload_duration_seconds_count"), 1);
  EXPECT_EQ(metric(during, "mltfarm_bootstrap_duration_seconds_count"), 1);
  // The job's own numbers, as GetJob reports them.
  const JobStatus st = c.get(a.jobId);
  ASSERT_GT(st.b, 0);
  EXPECT_NEAR(metric(during, "mltfarm_job_b", job), st.b, 1e-9 * st.b);
  EXPECT_NEAR(metric(during, "mltfarm_job_b_relative_stderr", job), st.bStdErr / st.b, 1e-9);
  EXPECT_NEAR(metric(during, "mltfarm_job_bootstrap_seconds", job), st.bootstrapSeconds, 1e-9);
  EXPECT_GT(metric(during, "mltfarm_job_samples_total", job), 0);
  EXPECT_GT(metric(during, "mltfarm_job_samples_per_second", job), 0);
  const double acceptance = metric(during, "mltfarm_job_chain_acceptance_ratio", job);
  EXPECT_GT(acceptance, 0);
  EXPECT_LE(acceptance, 1);
  const double progress = metric(during, "mltfarm_job_progress_ratio", job);
  EXPECT_GT(progress, 0);
  EXPECT_LT(progress, 1);

  ASSERT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  const std::string after = scrapeUntil(port, [&](const std::string& t) {
    return metric(t, "mltfarm_upload_duration_seconds_count") == mid.tasksTotal;
  });
  EXPECT_EQ(metric(after, "mltfarm_tasks_accepted_total"), mid.tasksTotal);
  EXPECT_GT(metric(after, "mltfarm_tasks_accepted_total"), metric(during, "mltfarm_tasks_accepted_total"));
  EXPECT_GT(metric(after, "mltfarm_upload_bytes_total"), metric(during, "mltfarm_upload_bytes_total"));
  EXPECT_EQ(metric(after, "mltfarm_upload_duration_seconds_count"), mid.tasksTotal);
  EXPECT_EQ(metric(after, "mltfarm_jobs", {"state=\"DONE\""}), 1);
  EXPECT_EQ(metric(after, "mltfarm_jobs", {"state=\"RUNNING\""}), 0);
  EXPECT_EQ(metric(after, "mltfarm_jobs_submitted_total"), 1);
  EXPECT_TRUE(std::isnan(metric(after, "mltfarm_job_b", job))) << "per-job series end with the job";

  // The worker's side: every task ran and was uploaded once; one bundle and one plan fetched, the rest
  // from its caches; the bytes it sent are the bytes the coordinator received.
  const std::string w = scrapeUntil(workerPort, [&](const std::string& t) {
    return metric(t, "mltfarm_worker_tasks_total", {"outcome=\"uploaded\""}) == mid.tasksTotal &&
           metric(t, "mltfarm_worker_tasks_running") == 0;
  });
  EXPECT_EQ(metric(w, "mltfarm_worker_tasks_total", {"outcome=\"uploaded\""}), mid.tasksTotal);
  EXPECT_EQ(metric(w, "mltfarm_worker_tasks_total", {"outcome=\"failed\""}), 0);
  EXPECT_EQ(metric(w, "mltfarm_worker_task_duration_seconds_count"), mid.tasksTotal);
  EXPECT_EQ(metric(w, "mltfarm_worker_cache_misses_total", {"cache=\"scene\""}), 1);
  EXPECT_EQ(metric(w, "mltfarm_worker_cache_hits_total", {"cache=\"scene\""}), mid.tasksTotal - 1);
  EXPECT_EQ(metric(w, "mltfarm_worker_cache_misses_total", {"cache=\"plan\""}), 1);
  EXPECT_EQ(metric(w, "mltfarm_worker_upload_bytes_total"), metric(after, "mltfarm_upload_bytes_total"));
  EXPECT_GT(metric(w, "mltfarm_worker_download_bytes_total"), 0);
  EXPECT_EQ(metric(w, "mltfarm_worker_tasks_running"), 0);

  // Every series the Grafana dashboard and the scrape config's documentation name exists.
  const std::string dashboard = readFile(std::string(MLTFARM_SOURCE_DIR) + "/deploy/grafana/mltfarm-dashboard.json");
  ASSERT_FALSE(dashboard.empty());
  std::set<std::string> names;
  const std::regex series("mltfarm_[a-z_]+");
  for (auto it = std::sregex_iterator(dashboard.begin(), dashboard.end(), series); it != std::sregex_iterator(); ++it)
    names.insert(it->str());
  EXPECT_GE(names.size(), 10u);
  for (const std::string& n : names)
    EXPECT_TRUE((during + after + w).find("\n" + n) != std::string::npos)
        << "the dashboard reads " << n << ", which no scrape shows";
}

TEST(FarmMetrics, RefusesAnAddressItCannotListenOn) {
  expectCoordinatorRefuses({"--metrics-listen", "not-an-address"}, "--metrics-listen not-an-address");
}

TEST(FarmShutdown, HealthIsNotServingBeforeTheDrain) {
  Farm farm;
  farm.startCoordinator({"--shutdown-grace", "5"});
  auto c = farm.client();
  ASSERT_TRUE(c.healthy());
  farm.coordinator->process.signal(SIGTERM);
  bool notServing = false;
  for (int i = 0; i < 200 && !notServing; ++i) {
    notServing = !c.healthy();
    if (!notServing) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(notServing) << "health still SERVING after SIGTERM";
  // Not serving, yet up: the calls in flight (and this one) are still answered during the grace period.
  EXPECT_NO_THROW(c.list());
  EXPECT_TRUE(farm.coordinator->process.running());
  EXPECT_EQ(farm.coordinator->process.wait(std::chrono::seconds(30)), 0);
  EXPECT_NE(readFile(farm.dir / "coordinator-0.log").find("event=not_serving"), std::string::npos);
}

}  // namespace
}  // namespace mlt::farm::test
