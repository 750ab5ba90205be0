// What an operator sees of a running coordinator (Coordinator::snapshot(), coordinator/snapshot.cpp):
// every job's status with the numbers behind the metrics and the web page (samples and chain acceptance
// of the accepted tasks), and every connected worker with the tasks it holds. Plain values copied under
// the coordinator's lock: readers never hold it.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/farm/farm_types.h"

namespace mlt::farm {

struct JobSnapshot {
  JobStatus status;
  uint32_t queuedTasks = 0;      // waiting to be leased
  uint64_t samplesAccepted = 0;  // pixel samples (sample methods) or mutations (chains) of accepted tasks
  double samplesPerSecond = 0;   // accepted since rendering started in this process, over the time since
  // Metropolis acceptance of the accepted tasks' chains; index = path length (pssmlt: index 0). Empty for
  // methods without chains.
  std::vector<uint64_t> proposedPerLength, acceptedPerLength;
  double submittedAt = 0;        // unix seconds
};

struct WorkerTask {
  std::string jobId, leaseId;
  uint32_t taskIndex = 0;
};

struct WorkerSnapshot {
  std::string workerId, hostname;
  int threads = 0;
  int64_t pid = 0;
  double secondsSinceSeen = 0;
  std::vector<WorkerTask> tasks;  // the leases it holds
};

struct FarmSnapshot {
  std::vector<JobSnapshot> jobs;  // by id
  std::vector<WorkerSnapshot> workers;
};

// A developed image of a job's accepted tasks, as PNG (the develop step of the previews and the final
// image: exact for the tasks it holds).
struct PreviewPng {
  std::string png;
  uint32_t tasks = 0;  // accepted tasks it holds
  bool final = false;  // the finished job's image
};

}  // namespace mlt::farm
