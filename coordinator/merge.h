// Merging and development: the one place where a job's partial results become an image, shared by the
// coordinator and `mltfarm merge` (offline), so both produce the same bytes. Tasks and the order in
// which they are summed: common/farm/tasks.h.
#pragma once
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "common/io/exr_io.h"
#include "common/job/executor.h"  // emptyPartial, runUnits
#include "common/methods/registry.h"
#include "common/farm/tasks.h"

namespace mlt::farm {

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
