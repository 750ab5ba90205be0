// Failing work units fail their job instead of being retried forever: a task that fails (the worker
// reports an exception, or its lease expires because the worker died) is requeued until it has failed
// --max-attempts times; then the job is FAILED with the error, visible in GetJob and `mltfarm status`,
// persisted across a coordinator restart, nothing more is leased, and the accepted tasks are kept.
#include <gtest/gtest.h>

#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

size_t countLines(const std::string& text, const std::vector<std::string>& needles) {
  size_t n = 0;
  std::istringstream lines(text);
  for (std::string l; std::getline(lines, l);) {
    bool all = true;
    for (const std::string& x : needles) all = all && l.find(x) != std::string::npos;
    n += all;
  }
  return n;
}

TEST(FarmFailure, AUnitThatAlwaysThrowsFailsItsJobAfterMaxAttempts) {
  Farm farm;
  farm.startCoordinator({"--max-attempts", "3"});
  // Every task holding work unit 5 throws on this worker, each task after 300 ms, so the failure takes
  // about a second and `mltfarm watch` below sees the job before it ends.
  farm.startWorker(2, {"--debug-fail-unit", "5", "--debug-task-delay-ms", "300"});
  auto c = farm.client();
  JobStatus bad = c.submit(cornellBox(), tinySettings("pssmlt"));  // 24 chains: unit 5 exists
  wire::SubmittedSettings small = tinySettings("bdpt");
  small.settings.spp = 4;  // units 0-3 only: never fails
  JobStatus good = c.submit(cornellBox(), small);
  ChildProcess watch({toolsDir() + "/mltfarm", "watch", bad.jobId, "--coordinator", farm.coordinator->address},
                     farm.dir / "watch.log", false);

  JobStatus s = farm.waitDone(bad.jobId);
  ASSERT_EQ(s.state, JobState::Failed) << describeStatus(s);
  EXPECT_NE(s.error.find("failed 3 times"), std::string::npos) << s.error;
  EXPECT_NE(s.error.find("work unit 5 fails on purpose"), std::string::npos) << s.error;
  EXPECT_GE(s.failedAttempts, 3u);
  EXPECT_EQ(farm.waitDone(good.jobId).state, JobState::Done) << "the other job must go on";

  // Nothing of the failed job is leased after the failure; exactly 3 attempts of its task were made.
  const std::string log = readFile(farm.dir / "coordinator-0.log");
  const size_t failedAt = log.find("job=" + bad.jobId + " event=state state=FAILED");
  ASSERT_NE(failedAt, std::string::npos);
  EXPECT_EQ(countLines(log.substr(failedAt), {"job=" + bad.jobId + " ", "event=leased"}), 0u);
  EXPECT_EQ(countLines(log, {"job=" + bad.jobId + " ", "event=task_failed"}), 3u);
  EXPECT_EQ(countLines(log, {"job=" + bad.jobId + " ", "event=requeued"}), 2u);
  const uint32_t acceptedBefore = s.tasksDone;

  // `mltfarm watch` follows the job to its failure (exit code != 0), one line per change: no two
  // consecutive lines that differ only in the ETA.
  EXPECT_NE(watch.wait(std::chrono::seconds(30)), 0);
  std::vector<std::string> lines;
  {
    std::istringstream in(readFile(farm.dir / "watch.log"));
    for (std::string l; std::getline(in, l);)
      if (l.rfind(bad.jobId + " ", 0) == 0) lines.push_back(l.substr(0, l.find("  eta ")));
  }
  ASSERT_GE(lines.size(), 2u);
  for (size_t i = 1; i < lines.size(); ++i) EXPECT_NE(lines[i], lines[i - 1]) << "line " << i << " repeats";
  EXPECT_NE(lines.back().find("FAILED"), std::string::npos) << lines.back();
  EXPECT_NE(lines.back().find("fails on purpose"), std::string::npos) << lines.back();

  // `mltfarm status` shows the error; fetching the result is refused with it.
  {
    ChildProcess cli({toolsDir() + "/mltfarm", "status", bad.jobId, "--coordinator", farm.coordinator->address},
                     farm.dir / "status.log", false);
    EXPECT_EQ(cli.wait(std::chrono::seconds(30)), 0);
  }
  EXPECT_NE(readFile(farm.dir / "status.log").find("fails on purpose"), std::string::npos)
      << readFile(farm.dir / "status.log");
  try {
    c.fetch(bad.jobId, farm.dir / "no.exr");
    ADD_FAILURE() << "fetch of a failed job succeeded";
  } catch (const RpcError& e) {
    EXPECT_EQ(e.code(), grpc::FAILED_PRECONDITION);
    EXPECT_NE(e.message().find("fails on purpose"), std::string::npos) << e.message();
  }

  // Persisted: a restarted coordinator still reports the failure and the accepted tasks.
  const std::string address = farm.coordinator->address;
  EXPECT_EQ(farm.coordinator->process.terminate(std::chrono::seconds(10)), 0);
  farm.startCoordinator({"--max-attempts", "3"}, address);
  JobStatus after = farm.client().get(bad.jobId);
  EXPECT_EQ(after.state, JobState::Failed);
  EXPECT_EQ(after.error, s.error);
  EXPECT_EQ(after.tasksDone, acceptedBefore);
  EXPECT_EQ(after.leasedTasks, 0u);
}

TEST(FarmFailure, AWorkerKilledRepeatedlyOnTheSameTaskFailsTheJob) {
  Farm farm;
  farm.startCoordinator({"--max-attempts", "2"});  // lease timeout 1.5 s (farm_harness.h)
  auto c = farm.client();
  JobStatus a = c.submit(cornellBox(), tinySettings("pssmlt"));
  farm.waitFor(a.jobId, [](const JobStatus& s) { return s.state == JobState::Running; });
  for (uint32_t kill = 1; kill <= 2; ++kill) {
    // Holds its lease without running it, then dies: the lease expires and the task is requeued first.
    ChildProcess& doomed = farm.startWorker(1, {"--debug-task-delay-ms", "100000"});
    farm.waitFor(a.jobId, [](const JobStatus& s) { return s.leasedTasks >= 1; });
    doomed.signal(SIGKILL);
    doomed.wait(std::chrono::seconds(10));
    JobStatus s = farm.waitFor(a.jobId, [kill](const JobStatus& st) { return st.failedAttempts >= kill; });
    EXPECT_EQ(s.failedAttempts, kill) << describeStatus(s);
  }
  JobStatus s = farm.waitDone(a.jobId);
  ASSERT_EQ(s.state, JobState::Failed) << describeStatus(s);
  EXPECT_NE(s.error.find("task 0 "), std::string::npos) << s.error;
  EXPECT_NE(s.error.find("failed 2 times"), std::string::npos) << s.error;
  EXPECT_NE(s.error.find("expired"), std::string::npos) << s.error;
  EXPECT_EQ(s.tasksDone, 0u);
}

}  // namespace
}  // namespace mlt::farm::test
