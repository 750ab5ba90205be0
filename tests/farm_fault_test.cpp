// The coordinator never dies from a job (issue 13): values a scene carries beyond the plan's limits are
// refused at submit with INVALID_ARGUMENT naming the field; a full or read-only state directory answers
// RESOURCE_EXHAUSTED / UNAVAILABLE, a background thread that cannot record a job's state (the reaper
// failing a job on a full disk) keeps it in memory and lives on, and nothing is lost once there is room. Real coordinator and worker processes on loopback.
#include <gtest/gtest.h>
#include <sys/mount.h>

#include <cerrno>
#include <cstring>
#include <fstream>

#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

std::string replaceOnce(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// Settings that take the film size, max depth and sample count from the scene (as `mltfarm submit
// --method pt --spp 1` does for all but the sample count).
wire::SubmittedSettings sceneDefaults() {
  wire::SubmittedSettings s = tinySettings("pt");
  s.hasSize = s.hasMaxDepth = s.hasSpp = false;
  s.settings.width = s.settings.height = 0;
  return s;
}

TEST(FarmFault, SceneValuesBeyondThePlanLimitsAreRefusedAtSubmitAndOtherJobsGoOn) {
  Farm farm;
  farm.startCoordinator();
  farm.startWorker(1);
  auto c = farm.client();
  const std::string box = readFile(cornellBox());
  auto small = [](std::string scene) {  // a 16x16 film with 2 samples per pixel unless the case says otherwise
    scene = replaceOnce(scene, "<default name=\"res\" value=\"256\"/>", "<default name=\"res\" value=\"16\"/>");
    return replaceOnce(scene, "<default name=\"spp\" value=\"64\"/>", "<default name=\"spp\" value=\"2\"/>");
  };
  struct Case {
    std::string scene, field, what;
  } cases[] = {
      {small(replaceOnce(box, "name=\"max_depth\" value=\"5\"", "name=\"max_depth\" value=\"2000\"")),
       "settings.max_depth", "the bundled Cornell box with max_depth 2000 (the issue's report)"},
      {replaceOnce(small(box), "<default name=\"res\" value=\"16\"/>", "<default name=\"res\" value=\"20000\"/>"),
       "settings.width", "a 20000 px film"},
      {replaceOnce(small(box), "<default name=\"spp\" value=\"2\"/>", "<default name=\"spp\" value=\"2000000\"/>"),
       "spp", "sample_count 2000000"},
  };
  for (const Case& k : cases) {
    expectRpcError([&] { c.submitBundle({{"cornell-box.xml", k.scene}}, "cornell-box.xml", sceneDefaults()); },
                   grpc::INVALID_ARGUMENT, k.field, k.what);
    ASSERT_TRUE(farm.coordinator->process.running()) << k.what << " ended the coordinator";
  }
  // The coordinator still serves: a job submitted after them completes, and none of them left a job behind.
  JobStatus good = c.submitBundle({{"cornell-box.xml", small(box)}}, "cornell-box.xml", sceneDefaults());
  EXPECT_EQ(farm.waitDone(good.jobId).state, JobState::Done);
  EXPECT_EQ(c.list().size(), 1u);
}

// A size-limited tmpfs mounted over the state directory (needs root, as CI's container runs).
struct SmallFilesystem {
  std::string dir;
  bool mounted = false;
  std::string why;
  SmallFilesystem(const std::string& d, const char* size) : dir(d) {
    fs::create_directories(dir);
    const std::string opts = std::string("size=") + size + ",mode=0755";
    mounted = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, opts.c_str()) == 0;
    if (!mounted) why = std::strerror(errno);
  }
  // `sub` (a directory on it) made read-only by a read-only bind mount of itself: a remount of the whole
  // tmpfs is refused while the coordinator holds its database open for writing.
  bool readOnly(const std::string& sub) {
    return ::mount(sub.c_str(), sub.c_str(), nullptr, MS_BIND, nullptr) == 0 &&
           ::mount(nullptr, sub.c_str(), nullptr, MS_REMOUNT | MS_BIND | MS_RDONLY, nullptr) == 0;
  }
  ~SmallFilesystem() {
    if (mounted) ::umount2(dir.c_str(), MNT_DETACH);
  }
};

// Writes until the filesystem is full; returns the bytes written.
uint64_t fill(const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  const std::string block(64 << 10, 'x');
  uint64_t n = 0;
  while (out.write(block.data(), std::streamsize(block.size())) && out.flush()) n += block.size();
  out.clear();
  while (out.write("x", 1) && out.flush()) ++n;
  return n;
}

TEST(FarmFault, AFullOrReadOnlyStateDirectoryAnswersWithAStatusAndTheCoordinatorLives) {
  Farm farm;
  SmallFilesystem small(farm.stateDir, "8m");
  if (!small.mounted)
    GTEST_SKIP() << "cannot mount a size-limited tmpfs on " << farm.stateDir << " (" << small.why
                 << "): this test needs root (CAP_SYS_ADMIN)";
  farm.startCoordinator({"--max-attempts", "1"});
  auto c = farm.client();
  // Two jobs planned (their plans recorded) before the disk fills. A worker holds a task of the first.
  JobStatus doomed = c.submit(cornellBox(), tinySettings("pt"));
  JobStatus a = c.submit(cornellBox(), tinySettings("pt"));
  ASSERT_EQ(farm.waitFor(a.jobId, [](const JobStatus& s) { return s.state == JobState::Running; }).state,
            JobState::Running);
  ChildProcess& holder = farm.startWorker(1, {"--debug-task-delay-ms", "100000"});
  farm.waitFor(doomed.jobId, [](const JobStatus& s) { return s.leasedTasks >= 1; });

  const uint64_t filler = fill(farm.stateDir + "/filler");
  EXPECT_GT(filler, 0u);
  // The holder dies: its lease expires and, out of attempts, the reaper fails the job; the database
  // cannot record that on a full disk, and the reaper thread lives on (the state is kept in memory).
  holder.signal(SIGKILL);
  JobStatus failed = farm.waitDone(doomed.jobId);
  EXPECT_EQ(failed.state, JobState::Failed) << describeStatus(failed);
  EXPECT_NE(readFile(farm.dir / "coordinator-0.log").find("event=state_not_recorded state=FAILED"), std::string::npos);
  ASSERT_TRUE(farm.coordinator->process.running());
  // A new bundle cannot be stored: RESOURCE_EXHAUSTED, and nothing recorded.
  const std::string other = readFile(cornellBox()) + "<!-- another bundle -->\n";
  expectRpcError([&] { c.submitBundle({{"scene.xml", other}}, "scene.xml", tinySettings("pt")); },
                 grpc::RESOURCE_EXHAUSTED, "No space left", "submit on a full disk");
  // The worker's results cannot be stored either: its uploads are answered RESOURCE_EXHAUSTED, the film
  // waits in its spool (off this disk) and the coordinator lives on.
  farm.startWorker(1);
  for (int i = 0; i < 600 && countOccurrences(readFile(farm.dir / "coordinator-0.log"), "No space left") < 2; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_GE(countOccurrences(readFile(farm.dir / "coordinator-0.log"), "No space left"), 2u);
  ASSERT_TRUE(farm.coordinator->process.running());
  EXPECT_EQ(c.get(a.jobId).state, JobState::Running);

  // Read-only: UNAVAILABLE.
  fs::remove(farm.stateDir + "/filler");
  const std::string scenes = farm.stateDir + "/scenes";
  ASSERT_TRUE(small.readOnly(scenes)) << std::strerror(errno);
  expectRpcError([&] { c.submitBundle({{"scene.xml", other}}, "scene.xml", tinySettings("pt")); },
                 grpc::UNAVAILABLE, "Read-only", "submit on a read-only state directory");
  ASSERT_TRUE(farm.coordinator->process.running());

  // Room again: the job completes with every task, and a new submission works.
  ASSERT_EQ(::umount2(scenes.c_str(), 0), 0) << std::strerror(errno);
  JobStatus done = farm.waitDone(a.jobId);
  EXPECT_EQ(done.state, JobState::Done) << describeStatus(done);
  JobStatus b = c.submitBundle({{"scene.xml", other}}, "scene.xml", tinySettings("pt"));
  EXPECT_EQ(farm.waitDone(b.jobId).state, JobState::Done);
  EXPECT_TRUE(farm.coordinator->process.running());
}

}  // namespace
}  // namespace mlt::farm::test
