// Restart: every job of the state directory comes back as it was left (see coordinator.h). A job that
// was planning is queued again (the bootstrap is a pure function of the job: it reruns to the same
// plan); a running job keeps its accepted tasks and requeues the rest; a finished one keeps its image,
// or is merged again if its image is missing.
#include <spdlog/spdlog.h>

#include <filesystem>

#include "coordinator/coordinator.h"
#include "proto/convert.h"

namespace mlt::farm {

namespace {

bool fileExists(const std::filesystem::path& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec);
}

}  // namespace

bool Coordinator::finalImagesExist(int64_t id) const {
  const std::filesystem::path dir = jobDir(id);
  return fileExists(dir / "image.exr") && fileExists(dir / "image.png");
}

void Coordinator::recover() {
  for (JobRecord& rec : store_->loadJobs()) {
    Job job;
    job.status.jobId = formatJobId(rec.id);
    job.status.name = rec.name;
    job.status.priority = rec.priority;
    job.status.sceneHash = rec.sceneHash;
    job.status.error = rec.error;
    JobState state = JobState(rec.state);
    try {
      v1::RenderSettings ps;
      ps.ParseFromString(rec.settings);
      wire::SubmittedSettings sub = wire::fromProto(ps);
      RenderSettings s = sub.settings;
      job.defines = sub.defines;
      job.status.method = s.method;
      job.status.width = s.width;
      job.status.height = s.height;
      if (!rec.plan.empty()) job.plan = std::make_shared<JobPlan>(wire::parseJobPlan(rec.plan));
    } catch (const std::exception& e) {
      spdlog::error("job={} event=reload_failed error=\"{}\"", job.status.jobId, e.what());
      state = JobState::Failed;
      job.status.error = std::string("state directory: ") + e.what();
    }
    job.rec = std::move(rec);
    int64_t id = job.rec.id;
    auto& j = jobs_.emplace(id, std::move(job)).first->second;
    if (state == JobState::Planning || (state == JobState::Queued) || (!isTerminal(state) && !j.plan)) {
      state = JobState::Queued;
    }
    if (state == JobState::Done && !finalImagesExist(id)) {
      // DONE in the database but the image is gone (deleted, or lost with a disk that did not keep it):
      // merge it again from the stored results (a task whose result is missing too is rendered again).
      spdlog::warn("job={} event=image_missing action=merge_again", j.status.jobId);
      state = JobState::Merging;
    }
    j.status.state = state;
    if (j.plan && (state == JobState::Running || state == JobState::Merging || state == JobState::Done)) {
      startRunning(j, /*loadResults=*/state != JobState::Done);  // the sum so far, from the result files
      if (state != JobState::Done) j.status.state = j.status.tasksDone == j.tasks.size() ? JobState::Merging : JobState::Running;
    } else if (j.plan && isTerminal(state)) {
      startRunning(j, false);  // failed or cancelled: show what was accepted (it is kept), lease nothing
      j.pending.clear();
    }
    refreshProgress(j);
    spdlog::info("job={} event=reloaded state={} tasks_done={}/{}", j.status.jobId, jobStateName(j.status.state),
                 j.status.tasksDone, j.status.tasksTotal);
  }
}

}  // namespace mlt::farm
