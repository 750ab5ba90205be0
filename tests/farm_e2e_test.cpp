// The farm end to end, with real coordinator and worker processes on loopback: the image is
// byte-identical however many workers ran it, whichever of them died, whether the coordinator was
// killed and restarted, and when the partial EXRs are merged offline.
#include <gtest/gtest.h>

#include "coordinator/merge.h"
#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

// Renders the reference job (pssmlt, then bdpt) with `workers` worker processes; returns the two EXRs.
struct Rendered {
  std::string mltExr, bdptExr;
};
Rendered renderWith(Farm& farm, int workers, const std::string& tag) {
  farm.startCoordinator({"--keep-partials"});
  for (int i = 0; i < workers; ++i) farm.startWorker();
  auto c = farm.client();
  JobStatus a = c.submit(cornellBox(), tinySettings(Method::PSSMLT));
  JobStatus b = c.submit(cornellBox(), tinySettings(Method::BDPT));
  EXPECT_EQ(a.jobId, "job-1");
  EXPECT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  EXPECT_EQ(farm.waitDone(b.jobId).state, JobState::Done);
  Rendered r{farm.dir / (tag + "-mlt.exr"), farm.dir / (tag + "-bdpt.exr")};
  c.fetch(a.jobId, r.mltExr);
  c.fetch(b.jobId, r.bdptExr);
  return r;
}

class FarmE2E : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    reference_ = std::make_unique<Farm>();
    ref_ = renderWith(*reference_, 1, "one");
  }
  static void TearDownTestSuite() { reference_.reset(); }
  static std::unique_ptr<Farm> reference_;
  static Rendered ref_;
};
std::unique_ptr<Farm> FarmE2E::reference_;
Rendered FarmE2E::ref_;

TEST_F(FarmE2E, OneAndThreeWorkersGiveByteIdenticalImages) {
  Farm farm;
  Rendered three = renderWith(farm, 3, "three");
  const std::string one = readFile(ref_.mltExr);
  ASSERT_GT(one.size(), 1000u);
  EXPECT_EQ(one, readFile(three.mltExr)) << "pssmlt image depends on the worker count";
  EXPECT_EQ(readFile(ref_.bdptExr), readFile(three.bdptExr)) << "bdpt image depends on the worker count";
  // The three workers really shared the work.
  int workersThatUploaded = 0;
  for (size_t i = 0; i < farm.workers.size(); ++i)
    workersThatUploaded += countOccurrences(readFile(farm.dir / ("worker-" + std::to_string(i) + ".log")),
                                            "event=uploaded") > 0;
  EXPECT_GE(workersThatUploaded, 2);
}

TEST_F(FarmE2E, OfflineMergeOfPartialExrsGivesTheSameBytes) {
  const std::string partials = reference_->stateDir + "/jobs/job-1/partials";
  std::vector<std::string> parts;
  for (auto& e : fs::directory_iterator(partials)) parts.push_back(e.path().string());
  std::sort(parts.rbegin(), parts.rend());  // order of the arguments must not matter
  ASSERT_GT(parts.size(), 2u);
  const std::string out = reference_->dir / "merged.exr";
  mergePartialExrs(parts, out, "");
  EXPECT_EQ(readFile(out), readFile(ref_.mltExr));

  // Through the CLI as well.
  std::vector<std::string> argv{toolsDir() + "/mltfarm", "merge"};
  argv.insert(argv.end(), parts.begin(), parts.end());
  argv.insert(argv.end(), {"-o", reference_->dir / "merged-cli.exr"});
  ChildProcess cli(argv, reference_->dir / "merge-cli.log", false);
  EXPECT_EQ(cli.wait(std::chrono::seconds(60)), 0);
  EXPECT_EQ(readFile(reference_->dir / "merged-cli.exr"), readFile(ref_.mltExr));

  // Missing, duplicated and foreign parts are clear errors, never a wrong image.
  std::vector<std::string> missing(parts.begin() + 1, parts.end());
  try {
    mergePartialExrs(missing, reference_->dir / "bad.exr", "");
    ADD_FAILURE() << "merge with a missing task succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos) << e.what();
  }
  std::vector<std::string> twice = parts;
  twice.push_back(parts.front());
  try {
    mergePartialExrs(twice, reference_->dir / "bad.exr", "");
    ADD_FAILURE() << "merge with a duplicated task succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("twice"), std::string::npos) << e.what();
  }
  std::vector<std::string> foreign = parts;
  for (auto& e : fs::directory_iterator(reference_->stateDir + "/jobs/job-2/partials")) {
    foreign.back() = e.path().string();
    break;
  }
  try {
    mergePartialExrs(foreign, reference_->dir / "bad.exr", "");
    ADD_FAILURE() << "merge of two jobs succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("different renders"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(reference_->dir / "bad.exr"));
}

TEST_F(FarmE2E, WorkerKilledMidJobStillGivesByteIdenticalImage) {
  Farm farm;
  farm.startCoordinator();
  // The doomed worker holds every lease it takes for a while, so it is surely holding one when killed.
  ChildProcess& doomed = farm.startWorker(2, {"--debug-task-delay-ms", "100000"});
  auto c = farm.client();
  JobStatus a = c.submit(cornellBox(), tinySettings(Method::PSSMLT));
  farm.waitFor(a.jobId, [](const JobStatus& s) { return s.leasedTasks >= 2; });
  farm.startWorker(1);
  farm.waitFor(a.jobId, [](const JobStatus& s) { return s.tasksDone >= 2; });
  doomed.signal(SIGKILL);
  EXPECT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  c.fetch(a.jobId, farm.dir / "out.exr");
  EXPECT_EQ(readFile(farm.dir / "out.exr"), readFile(ref_.mltExr));
  EXPECT_GE(countOccurrences(readFile(farm.dir / "coordinator-0.log"), "event=lease_expired"), 1u);
  // The surviving worker exits cleanly on SIGTERM.
  EXPECT_EQ(farm.workers.back()->terminate(std::chrono::seconds(20)), 0);
  EXPECT_NE(readFile(farm.dir / "worker-1.log").find("event=stopped"), std::string::npos);
}

TEST_F(FarmE2E, WorkerStoppedWithSigtermReturnsItsLeases) {
  Farm farm;
  farm.startCoordinator({}, "");
  ChildProcess& slow = farm.startWorker(2, {"--debug-task-delay-ms", "100000"});
  auto c = farm.client();
  JobStatus a = c.submit(cornellBox(), tinySettings(Method::PSSMLT));
  farm.waitFor(a.jobId, [](const JobStatus& s) { return s.leasedTasks >= 2; });
  EXPECT_EQ(slow.terminate(std::chrono::seconds(20)), 0);
  // Returned at once, not after the lease timeout: nothing is leased any more.
  JobStatus s = c.get(a.jobId);
  EXPECT_EQ(s.leasedTasks, 0u) << describeStatus(s);
  EXPECT_NE(readFile(farm.dir / "coordinator-0.log").find("event=returned"), std::string::npos);
  farm.startWorker(1);
  EXPECT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  c.fetch(a.jobId, farm.dir / "out.exr");
  EXPECT_EQ(readFile(farm.dir / "out.exr"), readFile(ref_.mltExr));
}

TEST_F(FarmE2E, CoordinatorKilledAndRestartedResumesWithoutRecomputing) {
  Farm farm;
  farm.startCoordinator();
  const std::string address = farm.coordinator->address;
  farm.startWorker(1, {"--debug-task-delay-ms", "40"});
  auto c = farm.client();
  JobStatus a = c.submit(cornellBox(), tinySettings(Method::PSSMLT));
  JobStatus b = c.submit(cornellBox(), tinySettings(Method::BDPT));
  JobStatus before = farm.waitFor(a.jobId, [](const JobStatus& s) { return s.tasksDone >= 3; });
  ASSERT_EQ(before.state, JobState::Running) << "job finished before the kill; make it longer";
  farm.coordinator->process.signal(SIGKILL);
  farm.coordinator->process.wait(std::chrono::seconds(10));
  // Same state directory, same address: the worker reconnects on its own.
  farm.startCoordinator({}, address);
  EXPECT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  EXPECT_EQ(farm.waitDone(b.jobId).state, JobState::Done);
  c.fetch(a.jobId, farm.dir / "mlt.exr");
  c.fetch(b.jobId, farm.dir / "bdpt.exr");
  EXPECT_EQ(readFile(farm.dir / "mlt.exr"), readFile(ref_.mltExr));
  EXPECT_EQ(readFile(farm.dir / "bdpt.exr"), readFile(ref_.bdptExr));
  // Accepted tasks were not recomputed: the restarted coordinator reloaded K accepted tasks per job and
  // accepted exactly the remaining T - K.
  const std::string log1 = readFile(farm.dir / "coordinator-1.log");
  for (const std::string& job : {a.jobId, b.jobId}) {
    const size_t at = log1.find("job=" + job + " event=reloaded");
    ASSERT_NE(at, std::string::npos) << job;
    const std::string line = log1.substr(at, log1.find('\n', at) - at);
    unsigned done = 0, total = 0;
    ASSERT_EQ(std::sscanf(line.c_str() + line.find("tasks_done=") + 11, "%u/%u", &done, &total), 2) << line;
    size_t acceptedAfter = 0;
    std::istringstream lines(log1);
    for (std::string l; std::getline(lines, l);)
      acceptedAfter += l.find("job=" + job + " task=") != std::string::npos && l.find("event=accepted") != std::string::npos;
    EXPECT_EQ(acceptedAfter, total - done) << job << ": " << line;
    if (job == a.jobId) EXPECT_GE(done, 3u);
  }
}

}  // namespace
}  // namespace mlt::farm::test
