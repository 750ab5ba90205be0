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

#include "common/methods/registry.h"
#include "common/render/render_scene.h"

namespace mlt::farm {

struct TaskRange {
  uint32_t begin = 0, end = 0;  // work units [begin, end)
};

// Bytes of a film's raw sums: pixel sums (3 doubles), pixel counts (1) and 3 per splat layer, per pixel.
// The same size as the wire's dense film encoding (proto/convert.h filmByteSize).
uint64_t rawFilmBytes(int width, int height, size_t splatLayers = 1);

// A unit's work: its mutations (Markov chains) or pixel samples (pt, lt, bdpt).
uint64_t unitWork(const JobPlan& plan, const WorkUnit& u);

// The tasks of a plan. Many tasks balance many workers, make progress and previews fine-grained and a
// lost task cheap; but every task carries a whole film (megabytes at 256x256: encoded, sent, stored,
// summed), so their number is bounded by what the films may cost next to the work:
//   T = min(units, 64, max(4, 512 MiB / film), max(kMinTasks, max(64 MiB, 4 bytes x work) / film))
// with film = the raw bytes of the plan's film, every splat layer it holds (RenderMethod::filmLayers). A
// small film (the tests' 32x32) keeps 64 tasks; the README's default job (256x256, 16.8 M mutations, mmlt
// films of 11 layers, 19 MB) gets kMinTasks: at least that many steps of progress, and tasks for a few
// workers to share.
inline constexpr uint64_t kMinTasks = 8;
std::vector<TaskRange> splitTasks(const JobPlan& plan);

// Runs units [range.begin, range.end), up to `parallelism` at a time, summing them in index order into a
// zero partial (the executor, common/job/executor.h). Returns false (result incomplete) if `cancel`
// becomes true between units.
bool runTask(const RenderScene& scene, const JobPlan& plan, TaskRange range, PartialResult& out,
             const std::atomic<bool>* cancel = nullptr, size_t parallelism = 1);

}  // namespace mlt::farm
