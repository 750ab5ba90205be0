// Durability under kill -9 at exactly chosen points (issue 13): the coordinator is started with the
// test-only --debug-crash-at POINT[:N] (coordinator/crash_point.h) and SIGKILLs itself there: after a film
// is received but before it is recorded, after it is recorded but before the reply, during the final
// merge. It is restarted on the same state directory and address, and the final image is byte-identical
// to an undisturbed run. And a DONE job whose image is missing is merged again at start-up.
#include <gtest/gtest.h>

#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

class FarmCrash : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    reference_ = std::make_unique<Farm>();
    reference_->startCoordinator();
    reference_->startWorker(1);
    auto c = reference_->client();
    JobStatus a = c.submit(cornellBox(), tinySettings("pssmlt"));
    if (reference_->waitDone(a.jobId).state != JobState::Done) return;
    c.fetch(a.jobId, reference_->dir / "reference.exr");
    image_ = readFile(reference_->dir / "reference.exr");
  }
  static void TearDownTestSuite() { reference_.reset(); }
  void SetUp() override { ASSERT_GT(image_.size(), 1000u) << "the undisturbed reference run failed"; }

  // Runs the reference job on a coordinator armed with `crashAt`; expects it to die there, restarts
  // it and returns the final image.
  static std::string renderThroughCrash(Farm& farm, const std::string& crashAt) {
    farm.startCoordinator({"--debug-crash-at", crashAt});
    const std::string address = farm.coordinator->address;
    farm.startWorker(1);
    JobStatus a = farm.client().submit(cornellBox(), tinySettings("pssmlt"));
    const std::optional<int> rc = farm.coordinator->process.wait(std::chrono::seconds(120));
    EXPECT_EQ(rc.value_or(-1), 128 + SIGKILL) << crashAt << ": the coordinator did not die at its crash point";
    const std::string point = crashAt.substr(0, crashAt.find(':'));
    EXPECT_NE(readFile(farm.dir / "coordinator-0.log").find("event=crash_point point=" + point), std::string::npos);
    farm.startCoordinator({}, address);  // same state directory and address: the worker reconnects
    EXPECT_EQ(farm.waitDone(a.jobId).state, JobState::Done) << crashAt;
    farm.client().fetch(a.jobId, farm.dir / "out.exr");
    return readFile(farm.dir / "out.exr");
  }
  static std::unique_ptr<Farm> reference_;
  static std::string image_;
};
std::unique_ptr<Farm> FarmCrash::reference_;
std::string FarmCrash::image_;

TEST_F(FarmCrash, KilledAfterAFilmIsReceivedBeforeItIsRecorded) {
  Farm farm;
  EXPECT_EQ(renderThroughCrash(farm, "upload-received:3"), image_);
}

TEST_F(FarmCrash, KilledAfterAFilmIsRecordedBeforeTheReply) {
  Farm farm;
  EXPECT_EQ(renderThroughCrash(farm, "upload-recorded:3"), image_);
  // The third film was kept: the restarted coordinator reloaded it rather than waiting for it again.
  const std::string log = readFile(farm.dir / "coordinator-1.log");
  const size_t at = log.find("event=reloaded");
  ASSERT_NE(at, std::string::npos) << log;
  unsigned done = 0;
  ASSERT_EQ(std::sscanf(log.c_str() + log.find("tasks_done=", at) + 11, "%u", &done), 1);
  EXPECT_GE(done, 3u);
}

TEST_F(FarmCrash, KilledDuringTheFinalMerge) {
  Farm farm;
  EXPECT_EQ(renderThroughCrash(farm, "final-merge"), image_);
  EXPECT_FALSE(fs::exists(farm.stateDir + "/jobs/job-1/image.tmp.exr")) << "the merge was redone and committed";
}

// Before: the job came back DONE with no image and FetchResult failed for good.
TEST_F(FarmCrash, DoneJobWhoseImageIsMissingIsMergedAgainAtStartup) {
  Farm farm;
  farm.startCoordinator();
  const std::string address = farm.coordinator->address;
  farm.startWorker(1);
  JobStatus a = farm.client().submit(cornellBox(), tinySettings("pssmlt"));
  ASSERT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  EXPECT_EQ(farm.coordinator->process.terminate(std::chrono::seconds(10)), 0);
  fs::remove(farm.stateDir + "/jobs/job-1/image.exr");
  farm.startCoordinator({}, address);
  EXPECT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  farm.client().fetch(a.jobId, farm.dir / "out.exr");
  EXPECT_EQ(readFile(farm.dir / "out.exr"), image_);
  EXPECT_NE(readFile(farm.dir / "coordinator-1.log").find("event=image_missing"), std::string::npos);
}

}  // namespace
}  // namespace mlt::farm::test
