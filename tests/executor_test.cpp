// The one executor of work units (common/job/executor.h): results are merged strictly in index order
// whatever the parallelism, issuing stops when asked, a cancelled task reports itself incomplete, and a
// real plan's merged film is bit-identical for any parallelism.
#include "common/job/executor.h"
#include "common/methods/registry.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <memory>
#include <vector>

#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

TEST(Executor, MergesInIndexOrderAndStopsIssuingWhenAsked) {
  for (size_t parallelism : {size_t(1), size_t(4)}) {
    std::vector<size_t> order;
    std::atomic<int> runs{0};
    UnitExecution e;
    e.parallelism = parallelism;
    e.issue = [](size_t i) { return i < 37; };
    e.run = [&](size_t i) {
      ++runs;
      PartialResult r;
      r.units = {uint32_t(i)};
      r.samples = i;
      return r;
    };
    e.merge = [&](size_t i, PartialResult& r) {
      EXPECT_EQ(r.samples, i);
      order.push_back(i);
    };
    EXPECT_EQ(executeUnits(e), 37u) << parallelism;
    EXPECT_EQ(runs.load(), 37);
    ASSERT_EQ(order.size(), 37u);
    for (size_t i = 0; i < order.size(); ++i) EXPECT_EQ(order[i], i) << "parallelism " << parallelism;
  }
  UnitExecution incomplete;
  incomplete.issue = nullptr;
  EXPECT_THROW(executeUnits(incomplete), std::invalid_argument);
}

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(16, 12));
  return *scene;
}

bool sameSums(const Film& a, const Film& b) {
  if (a.splatLayerCount() != b.splatLayerCount()) return false;
  for (size_t l = 0; l < a.splatLayerCount(); ++l)
    if (a.hasSplatLayer(l) != b.hasSplatLayer(l) ||
        (a.hasSplatLayer(l) &&
         std::memcmp(a.splatLayer(l).data(), b.splatLayer(l).data(), a.pixelCount() * sizeof(RGBd)) != 0))
      return false;
  return std::memcmp(a.pixelSums().data(), b.pixelSums().data(), a.pixelCount() * sizeof(RGBd)) == 0;
}

TEST(Executor, AnyParallelismGivesTheSameSumsAsATask) {
  for (std::string m : {"bdpt", "mmlt"}) {
    RenderSettings s;
    s.method = m;
    s.integrator.maxDepth = 4;
    s.spp = 8;
    s.samplesPerUnit = 1;
    s.mutationsPerPixel = 16;
    s.bootstrapSamples = 4096;
    s.chains = 12;
    const JobPlan plan = planJob(cornell(), s);
    const uint32_t n = uint32_t(plan.units.size());
    PartialResult task;
    ASSERT_TRUE(runUnits(cornell(), plan, 0, n, task));
    PartialResult parallel;
    UnitExecution e;
    e.parallelism = 4;
    e.issue = [&](size_t i) { return i < n; };
    e.run = [&](size_t i) { return runWorkUnit(cornell(), plan, plan.units[i]); };
    e.merge = [&](size_t, PartialResult& r) { parallel.add(r); };
    EXPECT_EQ(executeUnits(e), size_t(n));
    EXPECT_TRUE(sameSums(task.film, parallel.film)) << m.c_str();
    EXPECT_EQ(task.units, parallel.units);
    EXPECT_EQ(task.stats.largeStepSums, parallel.stats.largeStepSums) << m.c_str();

    std::atomic<bool> cancel{true};
    PartialResult cancelled;
    EXPECT_FALSE(runUnits(cornell(), plan, 0, n, cancelled, &cancel));
    EXPECT_TRUE(cancelled.units.empty());
    EXPECT_THROW(runUnits(cornell(), plan, 0, n + 1, cancelled), std::invalid_argument);
  }
}

}  // namespace
}  // namespace mlt
