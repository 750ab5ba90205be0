// A worker's last task uses every thread (worker/worker.cpp). The worker runs each task on a thread of
// its own inside one TBB arena of `threads` slots, with executor.h unitsInFlight units of the task in
// flight; when one task is left, its units must run on every thread.
//
// The test is a rendezvous, not a timing: a toy method whose last two units each wait until the other
// has started (up to a generous timeout). Every task holds two units (128 units make 64 tasks); the
// other units return at once. The two units of the last task meet only if two threads run that task's
// units at the same time. It fails when a task runs its units one at a time (checked: with one unit in
// flight it times out). It does not reliably catch the arena's old reserved slot (see worker.cpp): that
// locked TBB's worker out only when the last task's thread had taken the unreserved slot, which depends
// on when the tasks before it leave; a per-thread perf profile of the README's job showed it.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>

#include "common/methods/registry.h"
#include "tests/farm/farm_harness.h"
#include "tests/farm/in_process_farm.h"

namespace mlt {
namespace {

constexpr uint32_t kUnits = 128;
constexpr auto kPatience = std::chrono::seconds(10);
constexpr int kJobs = 8;  // a scheduling race gets several chances

std::atomic<int> gStarted{0};  // how many of the last two units have started
std::atomic<int> gMet{0};      // how many of them saw the other one start

class RendezvousMethod final : public RenderMethod {
 public:
  std::string name() const override { return "rendezvous"; }
  std::string description() const override { return "its last two units wait for each other (tests only)"; }
  MethodFamily family() const override { return MethodFamily::Samples; }
  JobPlan plan(const RenderScene&, const RenderSettings& settings) const override {
    return farm::test::sampleUnitsPlan(settings, kUnits);
  }
  PartialResult runUnit(const RenderScene&, const JobPlan& plan, const WorkUnit& unit) const override {
    if (unit.index >= kUnits - 2) {
      gStarted.fetch_add(1);
      const auto deadline = std::chrono::steady_clock::now() + kPatience;
      while (gStarted.load() < 2 && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      if (gStarted.load() >= 2) gMet.fetch_add(1);
    }
    PartialResult r;
    r.film = Film(plan.settings.width, plan.settings.height);
    for (int y = 0; y < plan.settings.height; ++y)  // one sample per pixel, as unitWork counts them
      for (int x = 0; x < plan.settings.width; ++x) r.film.addSample(Vec2(x + 0.5f, y + 0.5f), Color(1, 1, 1));
    r.samples = r.film.pixelCount();
    r.units = {unit.index};
    return r;
  }
  std::vector<Color> develop(const JobPlan&, const PartialResult& merged) const override {
    return merged.film.develop(0.0);
  }
  void addMetadata(const JobPlan&, const PartialResult&, ImageMetadata&) const override {}
};

TEST(WorkerThreads, TheLastTaskRunsItsUnitsOnEveryThread) {
  static const bool registered = [] {
    registerMethod(std::make_unique<RendezvousMethod>());
    return true;
  }();
  (void)registered;
  farm::WorkerOptions wo;
  wo.threads = 2;
  farm::test::InProcessFarm farm(1, wo);
  wire::SubmittedSettings s;
  s.settings.method = "rendezvous";
  s.settings.width = 8;
  s.settings.height = 8;
  s.hasSize = true;
  farm::FarmClient client(farm.channel());
  for (int job = 0; job < kJobs; ++job) {
    gStarted = 0;
    gMet = 0;
    const farm::JobStatus submitted = client.submit(farm::test::cornellBox(), s);
    const farm::JobStatus done =
        client.watch(submitted.jobId, [](const farm::JobStatus&) {}, std::chrono::seconds(120));
    ASSERT_EQ(done.state, farm::JobState::Done) << farm::describeStatus(done);
    ASSERT_EQ(done.tasksTotal, kUnits / 2) << "the test needs tasks of two units";
    ASSERT_EQ(gStarted.load(), 2);
    ASSERT_EQ(gMet.load(), 2) << "job " << job << ": the last task's two units never ran at the same time: the "
                              << "worker ran the task on one thread while the other was free";
  }
}

}  // namespace
}  // namespace mlt
