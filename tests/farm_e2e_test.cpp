// The farm end to end, with real coordinator and worker processes on loopback: the image is
// byte-identical however many workers ran it, whichever of them died, whether the coordinator was
// killed and restarted, and when the partial EXRs are merged offline.
#include <gtest/gtest.h>

#include "common/io/exr_io.h"
#include "common/mlt/develop.h"
#include "coordinator/merge.h"
#include "tests/farm/farm_harness.h"

#include <cmath>
#include <cstring>

namespace mlt::farm::test {
namespace {

// More work units than the 64 tasks a job is split into, so that tasks hold several units and the farm
// sums them in another grouping than the in-process renderer (unit by unit).
constexpr int kManyUnits = 96;
wire::SubmittedSettings bdptJob() {
  wire::SubmittedSettings s = tinySettings("bdpt");
  s.settings.spp = kManyUnits;  // one sample per unit
  return s;
}
wire::SubmittedSettings mmltJob() {
  wire::SubmittedSettings s = tinySettings("mmlt");
  s.settings.chains = kManyUnits;
  return s;
}

// Renders the reference jobs (pssmlt, bdpt, mmlt) with `workers` worker processes; returns the EXRs.
struct Rendered {
  std::string mltExr, bdptExr, mmltExr;
};
Rendered renderWith(Farm& farm, int workers, const std::string& tag) {
  farm.startCoordinator({"--keep-partials"});
  for (int i = 0; i < workers; ++i) farm.startWorker();
  auto c = farm.client();
  JobStatus a = c.submit(cornellBox(), tinySettings("pssmlt"));
  JobStatus b = c.submit(cornellBox(), bdptJob());
  JobStatus m = c.submit(cornellBox(), mmltJob());
  EXPECT_EQ(a.jobId, "job-1");
  EXPECT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  EXPECT_EQ(farm.waitDone(b.jobId).state, JobState::Done);
  EXPECT_EQ(farm.waitDone(m.jobId).state, JobState::Done);
  Rendered r{farm.dir / (tag + "-mlt.exr"), farm.dir / (tag + "-bdpt.exr"), farm.dir / (tag + "-mmlt.exr")};
  c.fetch(a.jobId, r.mltExr);
  c.fetch(b.jobId, r.bdptExr);
  c.fetch(m.jobId, r.mmltExr);
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
  EXPECT_EQ(readFile(ref_.mmltExr), readFile(three.mmltExr)) << "mmlt image depends on the worker count";
  // The three workers really shared the work.
  int workersThatUploaded = 0;
  for (size_t i = 0; i < farm.workers.size(); ++i)
    workersThatUploaded += countOccurrences(readFile(farm.dir / ("worker-" + std::to_string(i) + ".log")),
                                            "event=uploaded") > 0;
  EXPECT_GE(workersThatUploaded, 2);
}

// `mltfarm render --in-process` merges unit by unit, the farm task by task: the pixels are the same bits
// (every unit's sums are quantized, common/job/sample_job.h and common/mlt/develop.h). The files differ
// only in metadata (the farm's job id, the in-process run's wall time), so the pixels are compared.
TEST_F(FarmE2E, InProcessRenderGivesTheSamePixelsAsTheFarm) {
  struct Case {
    const char* method;
    std::string farmExr;
    int spp, chains;
  };
  for (const Case& k : {Case{"bdpt", ref_.bdptExr, kManyUnits, 24}, Case{"mmlt", ref_.mmltExr, 8, kManyUnits},
                        Case{"pssmlt", ref_.mltExr, 8, 24}}) {
    const char* method = k.method;
    const std::string& farmExr = k.farmExr;
    const std::string out = reference_->dir / (std::string("inprocess-") + method + ".exr");
    ChildProcess cli({toolsDir() + "/mltfarm", "render", cornellBox(), "-o", out, "--in-process", "-q", "-m", method,
                      "--seed", "7", "--width", "32", "--height", "32", "--spp", std::to_string(k.spp),
                      "--samples-per-unit", "1", "--mutations-per-pixel", "8", "--chains", std::to_string(k.chains),
                      "--bootstrap", "4000", "--max-depth", "4", "--threads", "2"},
                     reference_->dir / (std::string("inprocess-") + method + ".log"), false);
    ASSERT_EQ(cli.wait(std::chrono::seconds(120)), 0) << method;
    const ExrImage local = readExr(out), farm = readExr(farmExr);
    ASSERT_EQ(local.width, farm.width);
    ASSERT_EQ(local.height, farm.height);
    ASSERT_EQ(local.metadata.numbers.at("workUnits"), farm.metadata.numbers.at("workUnits")) << method;
    if (k.spp == kManyUnits || k.chains == kManyUnits)  // tasks really group several units
      EXPECT_LT(farm.metadata.numbers.at("farm.tasks"), farm.metadata.numbers.at("workUnits")) << method;
    EXPECT_EQ(std::memcmp(local.rgb.data(), farm.rgb.data(), local.rgb.size() * sizeof(Color)), 0)
        << method << ": in-process pixels differ from the farm's";
    if (std::string(method) != "bdpt") {  // b refined by the large steps: their sums merge exactly too
      EXPECT_EQ(local.metadata.numbers.at("b"), farm.metadata.numbers.at("b")) << method;
      EXPECT_EQ(local.metadata.numbers.at("bStdErr"), farm.metadata.numbers.at("bStdErr")) << method;
      EXPECT_GT(local.metadata.numbers.at("bSamples"), local.metadata.numbers.at("bootstrapSamplesInB")) << method;
    }
    double sum = 0;
    for (const Color& c : local.rgb) sum += c.r + c.g + c.b;
    EXPECT_GT(sum, 0.0) << method;
  }
}

// What makes the grouping irrelevant: every partial film the farm accepted for bdpt (tasks of one or two
// sample units) holds sums that are multiples of 2^-kQuantumExp, so adding them is exact in double. (The
// developed floats above rarely show a grouping difference even without it: this checks the sums.)
TEST_F(FarmE2E, BdptPartialSumsAreQuantized) {
  size_t parts = 0, nonZero = 0;
  for (auto& e : fs::directory_iterator(reference_->stateDir + "/jobs/job-2/partials")) {
    const PartialExr p = readPartialExr(e.path().string());
    ASSERT_EQ(p.plan.settings.method, "bdpt");
    ++parts;
    for (size_t i = 0; i < p.result.film.pixelCount(); ++i)
      for (double v : {p.result.film.pixelSums()[i].r, p.result.film.pixelSums()[i].g, p.result.film.splatSums()[i].b}) {
        nonZero += v != 0;
        const double scaled = std::ldexp(v, kQuantumExp);
        ASSERT_EQ(scaled, std::floor(scaled)) << e.path() << ": sum " << v << " is not a multiple of 2^-" << kQuantumExp;
      }
  }
  EXPECT_EQ(parts, 64u);
  EXPECT_GT(nonZero, 1000u);
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
  JobStatus a = c.submit(cornellBox(), tinySettings("pssmlt"));
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
  JobStatus a = c.submit(cornellBox(), tinySettings("pssmlt"));
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
  JobStatus a = c.submit(cornellBox(), tinySettings("pssmlt"));
  JobStatus b = c.submit(cornellBox(), bdptJob());
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
    if (job == a.jobId) {
      EXPECT_GE(done, 3u);
    }
  }
}

}  // namespace
}  // namespace mlt::farm::test
