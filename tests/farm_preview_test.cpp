// Progressive previews (--preview-every): while a job runs, the coordinator writes a developed image of
// the tasks accepted so far, normalized by the samples they hold. Checked against the same units rendered
// and developed in this process (the job API), bit for bit.
#include <gtest/gtest.h>

#include <cstring>

#include "common/io/exr_io.h"
#include "common/farm/scene_loading.h"
#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

TEST(FarmPreview, PreviewOfAcceptedTasksWhileTheJobRuns) {
  Farm farm;
  farm.startCoordinator({"--preview-every", "0.1"});
  // One slow single-thread worker: tasks are leased one at a time in order, so a preview holds tasks
  // 0..k-1 (one unit each here).
  farm.startWorker(1, {"--debug-task-delay-ms", "150"});
  auto c = farm.client();
  wire::SubmittedSettings s = tinySettings("pt");
  s.settings.spp = 16;  // 16 units of one sample per pixel = 16 tasks
  JobStatus a = c.submit(cornellBox(), s);
  const std::string preview = farm.stateDir + "/jobs/" + a.jobId + "/preview.exr";
  JobStatus mid = farm.waitFor(a.jobId, [&](const JobStatus&) { return fs::exists(preview); });
  ASSERT_EQ(mid.state, JobState::Running) << "finished before a preview was written";
  ASSERT_TRUE(fs::exists(farm.stateDir + "/jobs/" + a.jobId + "/preview.png"));
  const ExrImage early = readExr(preview);
  const int units = int(early.metadata.numbers.at("workUnits"));
  EXPECT_GE(units, 1);
  EXPECT_LT(units, 16);
  EXPECT_EQ(early.metadata.numbers.at("spp"), double(units));  // normalized by the samples merged
  ASSERT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  EXPECT_GE(countOccurrences(readFile(farm.dir / "coordinator-0.log"), "event=preview "), 1u);

  // The same units in this process: plan, run units 0..units-1, merge, develop.
  const LocalUnits local = runUnitsLocally(cornellBox(), s, units);
  ASSERT_EQ(local.plan.units.size(), 16u);
  const std::vector<Color> expected = developImage(local.plan, local.merged);
  ASSERT_EQ(expected.size(), early.rgb.size());
  EXPECT_EQ(std::memcmp(expected.data(), early.rgb.data(), expected.size() * sizeof(Color)), 0)
      << "the preview is not the developed image of the first " << units << " units";
  // And it is not the final image (which holds all 16).
  c.fetch(a.jobId, farm.dir / "final.exr");
  const ExrImage final = readExr(farm.dir / "final.exr");
  EXPECT_NE(std::memcmp(final.rgb.data(), early.rgb.data(), expected.size() * sizeof(Color)), 0);
}

}  // namespace
}  // namespace mlt::farm::test
