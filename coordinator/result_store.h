// Accepted task results, one file each: STATE/jobs/job-<id>/results/task-NNNNNN.part (the partial
// result as proto/convert.h serializePartial writes it, zero runs left out, plus a checksum). A file is
// written durably (common/core/durable_file.h: temporary name, fsync, rename, fsync of the directory)
// before the upload is acknowledged, so neither a killed coordinator nor a power loss loses anything it
// accepted. A file torn anyway (a disk that lies) fails its checksum on reload and its task is rendered
// again.
//
// Why not the SQLite database any more: a task's film is megabytes, and the database wrote each one
// twice (WAL, then checkpoint, with an fsync per checkpoint) and read it back for the merge; the
// coordinator now merges results in memory as they arrive and reads these files only after a restart.
// Thread-safe: each call touches its own file.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/job/job_types.h"

namespace mlt::farm {

class ResultStore {
 public:
  explicit ResultStore(std::string jobsDir);  // STATE/jobs

  // Writes (job, task)'s result. A task's result is a pure function of the plan, so a second write of
  // the same task (a duplicate upload racing the first) writes the same bytes. Throws FarmError
  // (storage_error.h: RESOURCE_EXHAUSTED when the disk is full) or std::filesystem::filesystem_error.
  void put(int64_t job, uint32_t task, const PartialResult& result) const;
  std::vector<uint32_t> stored(int64_t job) const;  // ascending
  // Deletes (job, task)'s result (a film stored for a job that stopped running before it was counted).
  void remove(int64_t job, uint32_t task) const;
  // nullopt if the file is missing, torn or does not parse (the caller renders the task again).
  std::optional<PartialResult> load(int64_t job, uint32_t task, std::string* why = nullptr) const;

 private:
  std::string path(int64_t job, uint32_t task) const;
  std::string dir_;
};

}  // namespace mlt::farm
