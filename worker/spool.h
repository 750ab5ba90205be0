// Finished films waiting for their coordinator: when an upload fails because the coordinator cannot be
// reached, the film is written to the spool directory (DIR/<pid>-<n>.film: the upload's target and the
// partial result as proto/convert.h serializePartial writes it, with a checksum; written under a temporary
// name and renamed) and uploaded from there, oldest first, whenever the coordinator answers again: after a
// restart, a partition, however long. The spool holds at most `maxBytes`; a film that does not fit is
// retried from memory for a while and then dropped, as before the spool existed (its task is leased again
// elsewhere). A film the coordinator refuses for good (its lease was given away, the task accepted from
// another worker, the job cancelled) is removed. Films left by a worker process that died are taken over by
// the next worker started on the same directory.
#pragma once
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/job/job_types.h"
#include "worker/uploader.h"

namespace mlt::farm {

class FilmSpool {
 public:
  // Creates `dir`; takes over the films of worker processes that are no longer running.
  FilmSpool(std::string dir, uint64_t maxBytes);

  // Writes the film; false (nothing written) if it would not fit in maxBytes or cannot be written.
  bool put(const UploadTarget& target, const PartialResult& result);
  size_t size() const;            // films waiting
  uint64_t bytes() const;         // their bytes on disk
  // The leases of the films waiting that were given to `workerId` (its heartbeats keep them).
  std::vector<std::string> leaseIds(const std::string& workerId) const;

  enum class Outcome { Done, Retry };  // Done: delivered or refused for good (removed); Retry: try later
  // Uploads the waiting films, oldest first, through `upload`; stops at the first Retry. Returns the number
  // of films removed. One drain at a time (a second caller waits for the first).
  size_t drain(const std::function<Outcome(const UploadTarget&, const PartialResult&)>& upload);

 private:
  struct Entry {
    std::string path;
    UploadTarget target;
    uint64_t bytes = 0;
  };
  std::optional<Entry> adopt(const std::string& path);  // reads a film's target; nullopt (removed) if torn
  void remove(const Entry& e);

  std::string dir_;
  uint64_t maxBytes_;
  mutable std::mutex mu_;
  std::mutex drainMu_;
  std::deque<Entry> entries_;
  uint64_t bytes_ = 0;
  uint64_t next_ = 0;
};

}  // namespace mlt::farm
