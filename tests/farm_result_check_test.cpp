// The coordinator's check of an uploaded task result (coordinator/result_check.h), for b's strata layers:
// a real task of a pssmlt-bdpt job passes (its strata hold one count per large step), and a strata layer
// that disagrees with the large steps, or holds a count no chain can write, is refused with
// INVALID_ARGUMENT naming the layer. (The farm-level checks of films, units and sample counts run through
// real RPCs in farm_lease_test.)
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "common/farm/farm_types.h"
#include "common/farm/tasks.h"
#include "common/methods/registry.h"
#include "common/mlt/develop.h"
#include "common/render/render_scene.h"
#include "coordinator/result_check.h"
#include "tests/support/test_scenes.h"

namespace mlt::farm {
namespace {

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(16, 12));
  return *scene;
}

JobPlan chainPlan(const char* method) {
  RenderSettings s;
  s.method = method;
  s.seed = 3;
  s.integrator.maxDepth = 4;
  s.mutationsPerPixel = 16;
  s.bootstrapSamples = 2048;
  s.chains = 8;
  return planJob(cornell(), s);
}

// Task 0 of the plan, rendered: its units merged in order, splats folded in (what a worker uploads).
PartialResult task0(const JobPlan& plan, TaskRange* range) {
  *range = splitTasks(plan).front();
  PartialResult r;
  for (uint32_t u = range->begin; u < range->end; ++u) r.add(runWorkUnit(cornell(), plan, plan.units[u]));
  r.foldSplats();
  return r;
}

void expectRefused(const JobPlan& plan, TaskRange range, const PartialResult& r, const std::string& needle,
                   const std::string& what) {
  try {
    checkTaskResult(plan, 0, range, r);
    ADD_FAILURE() << what << ": accepted";
  } catch (const FarmError& e) {
    EXPECT_EQ(e.code(), FarmError::Code::InvalidArgument) << what;
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << what << ": '" << e.what() << "'";
  }
}

TEST(ResultCheck, StrataMustCountTheLargeSteps) {
  const JobPlan plan = chainPlan("pssmlt-bdpt");
  TaskRange range;
  const PartialResult good = task0(plan, &range);
  const size_t strata = bStrataLayer(0);
  ASSERT_TRUE(good.film.hasSplatLayer(strata)) << "pssmlt-bdpt keeps b's strata";
  ASSERT_GT(good.stats.largeStepSums.at(0).n, 0u);
  EXPECT_NO_THROW(checkTaskResult(plan, 0, range, good));

  const std::string field = "partial.splat_layers[" + std::to_string(strata) + "]";
  PartialResult extra = good;
  extra.film.splatLayer(strata)[5].r += 1;  // one large step more than the stats hold
  expectRefused(plan, range, extra, "large_step_sums[0].n", "a strata layer counting a step the stats lack");
  expectRefused(plan, range, extra, field, "the same, naming the layer");

  PartialResult fewer = good;
  fewer.stats.largeStepSums[0].n -= 1;
  expectRefused(plan, range, fewer, "large_step_sums[0].n", "stats holding a step fewer than the strata");

  PartialResult half = good;
  half.film.splatLayer(strata)[7].r += 0.5;  // on the quantization grid, but no whole count
  expectRefused(plan, range, half, "whole count", "half a large step");

  PartialResult negative = good;
  negative.film.splatLayer(strata)[9].b = -1;  // a sum of squares below zero
  expectRefused(plan, range, negative, field, "a negative sum of m^2");
}

// Every chain method's real task passes: pssmlt, pssmlt-bdpt and veach-mlt with their strata (one count per
// large step or b sample), mmlt and rjmlt with none (only their chain layers 1 + 2k, layer 0 and Kelemen
// MIS's large-step layers after them, develop.h (D7)).
TEST(ResultCheck, EveryChainMethodsRealTaskPasses) {
  for (const char* m : {"pssmlt", "pssmlt-bdpt", "veach-mlt", "mmlt", "rjmlt"}) {
    const JobPlan plan = chainPlan(m);
    TaskRange range;
    const PartialResult r = task0(plan, &range);
    const bool strata = std::string(m) == "pssmlt" || std::string(m) == "pssmlt-bdpt" || std::string(m) == "veach-mlt";
    EXPECT_EQ(r.film.hasSplatLayer(bStrataLayer(0)), strata) << m;
    const size_t slots = plan.norm.mutationsPerLength.size();
    if (!strata)
      for (uint32_t l : r.film.splatLayers())
        EXPECT_TRUE(l == 0 || (l <= maxChainFilmLayer(slots) && l % 2 == 1) || l >= largeStepLayer(0, slots))
            << m << " wrote layer " << l;
    EXPECT_NO_THROW(checkTaskResult(plan, 0, range, r)) << m;
  }
}

}  // namespace
}  // namespace mlt::farm
