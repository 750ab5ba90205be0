// Progressive previews (mltfarm-coordinator --preview-every SECONDS): while a job runs, every period the
// tasks accepted so far are merged in task order and developed into STATE/jobs/<id>/preview.exr and
// preview.png. developImage normalizes by what was merged: pixel samples / light paths for pt, lt and
// bdpt (exact estimates from fewer samples), the merged mutations for Markov chains (each chain is
// stationary, so any subset of chains estimates the image; for mmlt the lengths whose chains have not
// arrived yet are missing until they do). Written to a temporary name and renamed, so a reader never sees
// a half-written file. The final image never depends on previews.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <optional>
#include <fmt/format.h>

#include "coordinator/coordinator.h"

namespace fs = std::filesystem;

namespace mlt::farm {

void Coordinator::writePreview(int64_t id, std::unique_lock<std::mutex>& lock) {
  Job& job = jobs_.at(id);
  std::shared_ptr<const JobPlan> plan = job.plan;
  const JobIdentity identity{job.status.jobId, job.rec.sceneHash, job.rec.sceneFile};
  // The running sum (tasks [0, mergedTasks)) and the accepted tasks beyond it, copied under the lock and
  // added in task order outside it: the same additions, in the same order, as the final merge.
  PartialResult merged = job.merged;
  std::vector<PartialResult> later;
  for (const auto& [t, r] : job.waiting) later.push_back(r);
  const size_t accepted = job.mergedTasks + later.size();
  job.previewTasks = uint32_t(accepted);
  lock.unlock();
  try {
    for (const PartialResult& r : later) merged.add(r);
    const fs::path dir = jobDir(id);
    fs::create_directories(dir);
    writeFinalImages((dir / "preview.tmp.exr").string(), (dir / "preview.tmp.png").string(), identity, *plan, merged);
    fs::rename(dir / "preview.tmp.exr", dir / "preview.exr");
    fs::rename(dir / "preview.tmp.png", dir / "preview.png");
    spdlog::info("job={} event=preview tasks={}/{} units={}", identity.jobId, accepted,
                 splitTasks(*plan).size(), merged.units.size());
  } catch (const std::exception& e) {  // a full disk, say: the job goes on without a preview
    spdlog::warn("job={} event=preview_failed error=\"{}\"", identity.jobId, e.what());
  } catch (...) {
    spdlog::warn("job={} event=preview_failed error=\"unknown exception\"", identity.jobId);
  }
  lock.lock();
}

void Coordinator::previewLoop() {
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(opt_.previewEverySeconds));
  std::unique_lock lock(mu_);
  while (!stopping_) {
    changed_.wait_for(lock, period, [this] { return stopping_; });
    if (stopping_) break;
    std::vector<int64_t> due;
    for (auto& [id, job] : jobs_)
      if (job.status.state == JobState::Running && job.plan && job.status.tasksDone > job.previewTasks) due.push_back(id);
    for (int64_t id : due) {
      if (stopping_) break;
      writePreview(id, lock);
    }
  }
}

}  // namespace mlt::farm
