// The planner thread: bootstraps queued jobs (highest priority first) and hands finished ones to the
// merge (merge_job.cpp), one at a time, outside the lock.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fmt/format.h>

#include "common/farm/scene_loading.h"
#include "common/methods/chain_report.h"
#include "common/methods/registry.h"
#include "coordinator/coordinator.h"
#include "proto/convert.h"

namespace fs = std::filesystem;

namespace mlt::farm {

void Coordinator::plannerLoop() {
  std::unique_lock lock(mu_);
  while (!stopping_) {
    int64_t toMerge = -1, toPlan = -1;
    int bestPriority = 0;
    for (auto& [id, job] : jobs_) {
      if (job.status.state == JobState::Merging && toMerge < 0) toMerge = id;
      if (job.status.state == JobState::Queued && (toPlan < 0 || job.status.priority > bestPriority)) {
        toPlan = id;
        bestPriority = job.status.priority;
      }
    }
    // A job that cannot proceed fails with its reason (runGuarded); the thread goes on with the others.
    if (toMerge >= 0) {
      lock.unlock();
      runGuarded(toMerge, "merge", [&] { merge(toMerge); });
      lock.lock();
    } else if (toPlan >= 0) {
      lock.unlock();
      runGuarded(toPlan, "bootstrap", [&] { planOne(toPlan); });
      lock.lock();
    } else {
      work_.wait(lock);
    }
  }
}

void Coordinator::planOne(int64_t id) {
  std::string file, dir, jobId, recorded;
  RenderSettings settings;
  std::map<std::string, std::string> defines;
  {
    std::lock_guard lock(mu_);
    Job& job = jobs_.at(id);
    if (job.status.state != JobState::Queued) return;
    setState(job, JobState::Planning);
    dir = sceneDir(job.rec.sceneHash);
    file = (fs::path(dir) / job.rec.sceneFile).string();
    defines = job.defines;
    jobId = job.status.jobId;
    recorded = job.rec.settings;
  }
  std::shared_ptr<JobPlan> plan;
  std::string error;
  std::string record;
  try {
    v1::RenderSettings ps;  // checked at submit; a job recorded by an older build may still be refused here
    if (!ps.ParseFromString(recorded)) throw std::runtime_error("the recorded settings do not parse");
    settings = wire::fromProto(ps).settings;
    auto scene = buildRenderScene(loadSceneDesc(file, defines, dir), settings.width, settings.height);  // the bundle only
    spdlog::info("job={} event=bootstrap_start method={} bootstrap_samples={}", jobId, settings.method,
                 settings.bootstrapSamples);
    plan = std::make_shared<JobPlan>(planJob(*scene, settings));
    metrics_.bootstrapSeconds.Observe(plan->norm.bootstrapSeconds);
    spdlog::info("job={} event=bootstrap_done b={} b_stderr={} units={} seconds={:.3f}", jobId, plan->norm.b,
                 plan->norm.bStdErr, plan->units.size(), plan->norm.bootstrapSeconds);
    if (plan->units.empty()) error = "the plan has no work units";
    if (isMarkovChainMethod(settings.method))
      if (const std::string crowded = describeCrowdedStart(crowdedStart(*plan)); !crowded.empty())
        spdlog::warn("job={} event=crowded_start {}", jobId, crowded);
    record = wire::jobPlanBytes(*plan);
    wire::parseJobPlan(record);  // the plan must survive the wire
  } catch (const std::exception& e) {
    error = e.what();
  }
  std::lock_guard lock(mu_);
  Job& job = jobs_.at(id);
  if (job.status.state != JobState::Planning) return;  // cancelled meanwhile
  if (error.empty()) try {
    store_->setPlan(id, record, uint32_t(splitTasks(*plan).size()), int(JobState::Running));
  } catch (const std::exception& e) {  // disk full, read-only: without a recorded plan the job cannot run
    error = fmt::format("cannot record the plan: {}", e.what());
  }
  if (!error.empty()) {
    setState(job, JobState::Failed, "bootstrap: " + error);
    return;
  }
  job.plan = plan;
  job.status.state = JobState::Running;
  startRunning(job);
  touch(job);
}

}  // namespace mlt::farm
