// The local-farm path of `mltfarm render` (see farm_render.h).
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "common/io/exr_io.h"
#include "common/io/png_io.h"
#include "coordinator/embedded.h"
#include "tools/cli/farm_render.h"
#include "tools/cli/progress.h"

namespace mlt::cli {

ExrImage renderWithLocalFarm(const LocalRenderOptions& o, int workers, const std::string& farmDir) {
  if (o.settings.timeBudgetSeconds > 0 || o.techniqueImages)
    throw std::invalid_argument("--time and --technique-images need --in-process");
  if (!o.outExr.empty()) {  // fail before rendering, not after
    const std::filesystem::path dir = std::filesystem::absolute(o.outExr).parent_path();
    if (!std::filesystem::is_directory(dir))
      throw std::runtime_error(o.outExr + ": output directory " + dir.string() + " does not exist");
  }
  if (!farmDir.empty() && std::filesystem::exists(farmDir) && !std::filesystem::is_empty(farmDir))
    throw std::runtime_error("--farm-dir " + farmDir + ": not empty (a farm there would resume the jobs it holds); "
                             "give a new or empty directory");
  farm::EmbeddedFarmOptions e;
  e.scenePath = o.scenePath;
  e.stateDir = farmDir;
  e.settings.settings = o.settings;
  e.settings.hasSize = o.settings.width > 0 && o.settings.height > 0;
  if (o.maxDepth) e.settings.settings.integrator.maxDepth = *o.maxDepth;
  if (o.rrDepth) e.settings.settings.integrator.rrDepth = *o.rrDepth;
  e.settings.hasMaxDepth = o.maxDepth.has_value();
  e.settings.hasRrDepth = o.rrDepth.has_value();
  e.settings.hasSpp = o.sppGiven;
  e.settings.defines = o.defines;  // applied by the coordinator and every worker
  // One worker process running every thread by default: its tasks share the threads unit by unit, so
  // the job's last task does not leave a core idle (with one single-threaded process per core it would).
  const int threads = o.threads > 0 ? o.threads : int(std::max(1u, std::thread::hardware_concurrency()));
  e.workers = workers > 0 ? workers : 1;
  e.threadsPerWorker = std::max(1, threads / e.workers);
  e.outExr = o.outExr;
  const std::string png = o.outPng.empty() ? pngPathFor(o.outExr) : o.outPng;
  std::unique_ptr<ProgressBar> bar;
  if (o.showProgress)
    e.onStatus = [&](const farm::JobStatus& s) {
      if (!bar && s.tasksTotal > 0)
        bar = std::make_unique<ProgressBar>(std::string("render ") + s.method + " (local farm)", s.tasksTotal);
      if (bar) bar->update(s.tasksDone);
    };
  ExrImage img;
  if (!o.outExr.empty())
    e.afterFetch = [&] {  // the PNG with the requested exposure, from the fetched EXR, while the farm exits
      img = readExr(o.outExr);
      writePng(png, img.width, img.height, img.rgb, o.exposureStops);
    };
  farm::EmbeddedFarmResult r = farm::runEmbeddedFarm(e);
  if (bar) {
    char line[256];
    std::snprintf(line, sizeof line, "%s: %u work units in %u tasks on the local farm in %.2f s (startup %.2f s)",
                  r.status.method.c_str(), r.status.unitsTotal, r.status.tasksTotal, r.seconds, r.startupSeconds);
    bar->finish(line);
  }
  return img;
}

}  // namespace mlt::cli
