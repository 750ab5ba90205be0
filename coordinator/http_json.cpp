// JSON of the HTTP API (see http_json.h).
#include "coordinator/http_json.h"

namespace mlt::farm {

using nlohmann::json;

json jobJson(const JobSnapshot& j) {
  const JobStatus& s = j.status;
  json o;
  o["id"] = s.jobId;
  o["name"] = s.name;
  o["state"] = jobStateName(s.state);
  o["phase"] = s.phase;
  o["method"] = s.method;
  o["priority"] = s.priority;
  o["width"] = s.width;
  o["height"] = s.height;
  o["progress"] = s.state == JobState::Done ? 1.0 : s.workTotal ? double(s.workDone) / double(s.workTotal) : 0.0;
  o["tasks_done"] = s.tasksDone;
  o["tasks_total"] = s.tasksTotal;
  o["tasks_leased"] = s.leasedTasks;
  o["tasks_queued"] = j.queuedTasks;
  o["eta_seconds"] = s.etaSeconds >= 0 ? json(s.etaSeconds) : json(nullptr);
  o["elapsed_seconds"] = s.elapsedSeconds;
  o["b"] = s.b;
  o["b_stderr"] = s.bStdErr;
  o["b_relative_stderr"] = s.b > 0 ? json(s.bStdErr / s.b) : json(nullptr);
  o["bootstrap_seconds"] = s.bootstrapSeconds;
  o["samples"] = j.samplesAccepted;
  o["samples_per_second"] = j.samplesPerSecond;
  o["failed_attempts"] = s.failedAttempts;
  o["error"] = s.error;
  o["submitted_at"] = j.submittedAt;
  return o;
}

json workerJson(const WorkerSnapshot& w) {
  json tasks = json::array();
  for (const WorkerTask& t : w.tasks) tasks.push_back({{"job", t.jobId}, {"task", t.taskIndex}, {"lease", t.leaseId}});
  return {{"id", w.workerId}, {"host", w.hostname}, {"threads", w.threads}, {"pid", w.pid},
          {"seconds_since_seen", w.secondsSinceSeen}, {"tasks", tasks}};
}

json jobDetailJson(const JobSnapshot& j, const std::vector<WorkerSnapshot>& workers) {
  json o = jobJson(j);
  json acceptance = json::array();
  for (size_t k = 0; k < j.proposedPerLength.size(); ++k) {
    const uint64_t p = j.proposedPerLength[k], a = k < j.acceptedPerLength.size() ? j.acceptedPerLength[k] : 0;
    if (p == 0) continue;
    acceptance.push_back({{"path_length", k}, {"proposed", p}, {"accepted", a}, {"ratio", double(a) / double(p)}});
  }
  o["acceptance"] = acceptance;
  json ws = json::array();
  for (const WorkerSnapshot& w : workers) {
    WorkerSnapshot mine = w;
    std::erase_if(mine.tasks, [&](const WorkerTask& t) { return t.jobId != j.status.jobId; });
    if (!mine.tasks.empty()) ws.push_back(workerJson(mine));
  }
  o["workers"] = ws;
  return o;
}

}  // namespace mlt::farm
