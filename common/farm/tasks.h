// Tasks: what a worker leases and uploads. A job's work units are grouped into a fixed number of tasks
// (contiguous unit ranges, chosen from the plan alone, never from the number of workers); the
// coordinator accepts each task once, keyed by (job, task). Sums are always formed in unit-index order:
// within a task the worker adds units begin..end-1 to a zero film, the coordinator adds tasks 0..T-1 to
// a zero film. Floating-point addition is not associative, so this fixed order is what makes the image
// independent of worker count and arrival order.
#pragma once
#include <atomic>
#include <cstdint>
#include <vector>

#include "common/job/render_job.h"
#include "common/render/render_scene.h"

namespace mlt::farm {

struct TaskRange {
  uint32_t begin = 0, end = 0;  // work units [begin, end)
};

// Bytes of a film's raw sums: pixel sums (3 doubles), pixel counts (1) and 3 per splat layer, per pixel.
// The same size as the wire's dense film encoding (proto/convert.h filmByteSize).
uint64_t rawFilmBytes(int width, int height, size_t splatLayers = 1);

// At most 64 tasks, at least min(units, 4), and few enough that the stored partial films stay under
// ~512 MiB.
std::vector<TaskRange> splitTasks(const JobPlan& plan);

// Runs units [range.begin, range.end) in order, summing into a zero partial. Returns false (result
// incomplete) if `cancel` becomes true between units.
bool runTask(const RenderScene& scene, const JobPlan& plan, TaskRange range, PartialResult& out,
             const std::atomic<bool>* cancel = nullptr);

}  // namespace mlt::farm
