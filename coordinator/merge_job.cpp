// The final merge of a job whose tasks are all accepted: sums them in task order (the bytes never depend
// on arrival order), develops and writes image.exr + image.png, and records the refined b.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fmt/format.h>
#include <optional>

#include "common/job/mlt_job.h"
#include "coordinator/coordinator.h"
#include "proto/convert.h"

namespace fs = std::filesystem;

namespace mlt::farm {

void Coordinator::merge(int64_t id) {
  std::shared_ptr<const JobPlan> plan;
  JobIdentity identity;
  size_t tasks = 0;
  {
    std::lock_guard lock(mu_);
    Job& job = jobs_.at(id);
    plan = job.plan;
    identity = {job.status.jobId, job.rec.sceneHash, job.rec.sceneFile};
    tasks = job.tasks.size();
  }
  std::string error;
  std::optional<RefinedB> refined;  // b as the image was developed with (bootstrap + large steps)
  try {
    PartialResult merged = emptyPartial(*plan);
    for (uint32_t t = 0; t < tasks; ++t) {  // index order: the bytes never depend on arrival order
      std::optional<std::string> blob;
      {
        std::lock_guard lock(mu_);
        blob = store_->loadResult(id, t);
      }
      if (!blob) throw std::runtime_error(fmt::format("task {} has no stored result", t));
      merged.add(wire::parsePartial(*blob));
    }
    fs::path dir = jobDir(id);
    fs::create_directories(dir);
    writeFinalImages((dir / "image.tmp.exr").string(), (dir / "image.tmp.png").string(), identity, *plan, merged);
    if (isMarkovChainMethod(plan->settings.method)) refined = refinedB(plan->norm, merged.stats);
    fs::rename(dir / "image.tmp.exr", dir / "image.exr");
    fs::rename(dir / "image.tmp.png", dir / "image.png");
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
