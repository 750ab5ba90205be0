// Task splitting and running (see tasks.h).
#include "common/farm/tasks.h"

#include <algorithm>

#include "common/job/executor.h"  // runUnits

namespace mlt::farm {

uint64_t rawFilmBytes(int width, int height, size_t splatLayers) {
  return uint64_t(width) * uint64_t(height) * (4 + 3 * splatLayers) * sizeof(double);
}

uint64_t unitWork(const JobPlan& plan, const WorkUnit& u) {
  return findMethod(plan.settings.method).unitWork(plan, u);
}

std::vector<TaskRange> splitTasks(const JobPlan& plan) {
  const uint64_t units = plan.units.size();
  if (units == 0) return {};
  const size_t layers = findMethod(plan.settings.method).filmLayers(plan);
  const uint64_t filmBytes = std::max<uint64_t>(1, rawFilmBytes(plan.settings.width, plan.settings.height, layers));
  const uint64_t byMemory = std::max<uint64_t>(4, (512ull << 20) / filmBytes);
  uint64_t work = 0;
  for (const WorkUnit& u : plan.units) work += unitWork(plan, u);
  // Film traffic: free up to 64 MiB per job, beyond that 4 bytes per mutation or sample. A film costs
  // about 0.8 ns per raw byte on the two sides together (the worker encodes it; the coordinator decodes,
  // checks, stores and sums it; estimated from perf samples of the default job, not measured apart), a
  // mutation about 1 us of CPU: 4 bytes per mutation is about 0.3% of the job.
  const uint64_t traffic = std::max<uint64_t>(64ull << 20, 4 * work);
  const uint64_t byTraffic = std::max<uint64_t>(kMinTasks, traffic / filmBytes);
  const uint64_t T = std::min<uint64_t>({units, 64, byMemory, byTraffic});
  std::vector<TaskRange> tasks(T);
  for (uint64_t t = 0; t < T; ++t) tasks[t] = {uint32_t(t * units / T), uint32_t((t + 1) * units / T)};
  return tasks;
}

bool runTask(const RenderScene& scene, const JobPlan& plan, TaskRange range, PartialResult& out,
             const std::atomic<bool>* cancel, size_t parallelism) {
  // The one executor (common/job/executor.h).
  return runUnits(scene, plan, range.begin, range.end, out, cancel, parallelism);
}

}  // namespace mlt::farm
