// The JSON shapes of the coordinator's HTTP API (http_server.h), from the operator's snapshot.
//   job:    {id, name, state, phase, method, priority, width, height, progress (0..1), tasks_done,
//            tasks_total, tasks_leased, tasks_queued, eta_seconds (null when unknown), elapsed_seconds,
//            b, b_stderr, b_relative_stderr (null when b is 0), bootstrap_seconds, samples,
//            samples_per_second, failed_attempts, error, submitted_at}
//   detail: job + {acceptance: [{path_length, proposed, accepted, ratio}], workers: [worker holding a task
//            of this job]}
//   worker: {id, host, threads, pid, seconds_since_seen, tasks: [{job, task, lease}]}
#pragma once
#include <nlohmann/json.hpp>

#include "coordinator/snapshot.h"

namespace mlt::farm {

nlohmann::json jobJson(const JobSnapshot& j);
nlohmann::json jobDetailJson(const JobSnapshot& j, const std::vector<WorkerSnapshot>& workers);
nlohmann::json workerJson(const WorkerSnapshot& w);

}  // namespace mlt::farm
