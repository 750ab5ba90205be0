// Tasks, merging and development: the one place where a job's partial results become an image, shared
// by the coordinator, the worker (which merges the units of a task) and `mltfarm merge` (offline), so
// all three produce the same bytes.
//
// A job's work units are grouped into a fixed number of *tasks* (contiguous unit ranges, chosen from
// the plan alone, never from the number of workers). A task is what a worker leases and uploads; the
// coordinator accepts each task once, keyed by (job, task). Sums are always formed in unit-index order:
// within a task the worker adds units begin..end-1 to a zero film, the coordinator adds tasks 0..T-1 to
// a zero film. Floating-point addition is not associative, so this fixed order is what makes the image
// independent of worker count and arrival order.
#pragma once
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "common/io/exr_io.h"
#include "common/job/executor.h"  // emptyPartial, runUnits
#include "common/methods/registry.h"

namespace mlt::farm {

struct TaskRange {
  uint32_t begin = 0, end = 0;  // work units [begin, end)
};

// At most 64 tasks, at least min(units, 4), and few enough that the stored partial films stay under
// ~512 MiB.
std::vector<TaskRange> splitTasks(const JobPlan& plan);


// Runs units [range.begin, range.end) in order, summing into a zero partial. Returns false (result
// incomplete) if `cancel` becomes true between units.
bool runTask(const RenderScene& scene, const JobPlan& plan, TaskRange range, PartialResult& out,
             const std::atomic<bool>* cancel = nullptr);

// Who a job is, for metadata.
struct JobIdentity {
  std::string jobId, sceneHash;
  std::string scene;  // the scene file's name inside its bundle
};

// The developed image's metadata: a pure function of the identity, the plan and the merged result.
ImageMetadata finalMetadata(const JobIdentity& id, const JobPlan& plan, const PartialResult& merged);
// Develops `merged` (sum of all tasks in order) and writes the EXR (and the PNG if pngPath is not empty).
void writeFinalImages(const std::string& exrPath, const std::string& pngPath, const JobIdentity& id,
                      const JobPlan& plan, const PartialResult& merged);

// Partial EXRs: one task's raw film (bit-exact) with everything needed to merge offline.
void writePartialExr(const std::string& path, const JobIdentity& id, const JobPlan& plan, uint32_t task,
                     const PartialResult& result);
struct PartialExr {
  JobIdentity id;
  std::string planBytes;
  JobPlan plan;
  uint32_t task = 0, tasks = 0;
  PartialResult result;
};
PartialExr readPartialExr(const std::string& path);  // std::runtime_error naming the file

// `mltfarm merge`: checks that the parts belong together (same job, scene hash, plan: b, size, method;
// no task twice; every task present, else names the missing ones), merges in task order and writes the
// developed image(s). Throws std::runtime_error on any mismatch.
void mergePartialExrs(const std::vector<std::string>& parts, const std::string& exrPath,
                      const std::string& pngPath);

}  // namespace mlt::farm
