// The final merge of a job whose tasks are all accepted: their sum in task order is already made (the
// coordinator adds each accepted task once the tasks before it are in, so the bytes never depend on
// arrival order); it is developed into image.exr + image.png, and the refined b is recorded.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fmt/format.h>
#include <optional>

#include "common/job/mlt_job.h"
#include "common/methods/chain_report.h"
#include "common/core/durable_file.h"
#include "coordinator/coordinator.h"
#include "coordinator/crash_point.h"

namespace fs = std::filesystem;

namespace mlt::farm {

void Coordinator::merge(int64_t id) {
  std::shared_ptr<const JobPlan> plan;
  JobIdentity identity;
  PartialResult merged;  // every task, summed in task order as they were accepted (upload.cpp)
  std::string error;
  {
    std::lock_guard lock(mu_);
    Job& job = jobs_.at(id);
    plan = job.plan;
    identity = {job.status.jobId, job.rec.sceneHash, job.rec.sceneFile};
    if (job.mergedTasks != job.tasks.size())
      error = fmt::format("task {} is accepted but not summed", job.mergedTasks);
    merged = std::move(job.merged);
    job.merged = {};
    job.waiting.clear();
  }
  std::optional<RefinedB> refined;  // b as the image was developed with (bootstrap + large steps)
  if (error.empty()) try {
    fs::path dir = jobDir(id);
    fs::create_directories(dir);
    writeFinalImages((dir / "image.tmp.exr").string(), (dir / "image.tmp.png").string(), identity, *plan, merged);
    if (isMarkovChainMethod(plan->settings.method)) {
      refined = refinedB(plan->norm, merged.stats, &merged.film);
      // The workers' wall time per move kind, summed (not in the image: its bytes do not depend on the run).
      const std::string rates = formatMoveRates(makeChainReport(*plan, merged));
      if (!rates.empty())
        spdlog::info("job={} event=move_rates per_thread=\"{}\"", identity.jobId, rates);
    }
    crashPoint("final-merge");
    // Durable before the job is DONE: a DONE job's image survives a power loss (and if it is missing
    // anyway, the restart merges it again, recovery.cpp).
    commitFileDurably((dir / "image.tmp.png").string(), (dir / "image.png").string());
    commitFileDurably((dir / "image.tmp.exr").string(), (dir / "image.exr").string());
  } catch (const std::exception& e) {
    error = e.what();
  }
  std::lock_guard lock(mu_);
  Job& job = jobs_.at(id);
  if (job.status.state != JobState::Merging) return;
  if (refined) {
    job.status.b = refined->total.b;
    job.status.bStdErr = refined->total.stdErr;
  }
  if (!error.empty()) setState(job, JobState::Failed, "merge: " + error);
  else setState(job, JobState::Done);
}

}  // namespace mlt::farm
