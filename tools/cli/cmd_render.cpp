// `mltfarm render SCENE.xml|SCENE.pbrt ... -o OUT.exr`: renders a scene and writes OUT.exr (with metadata) and
// OUT.png. By default through the local farm (a coordinator plus worker processes on loopback,
// tools/cli/farm_render.h); --in-process renders in this process. Both call the same job API.
#include <chrono>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "common/io/exr_io.h"
#include "common/methods/chain_report.h"
#include "tools/cli/commands.h"
#include "tools/cli/farm_render.h"
#include "tools/cli/render_local.h"
#include "tools/cli/settings_options.h"

namespace mlt::cli {
namespace {

// render's own options; the render settings are the shared group (settings_options.h).
struct RenderCliOptions {
  std::string scene, out, png, farmDir;
  int threads = 0, workers = 0;
  double time = 0;
  float exposure = 0;
  bool inProcess = false, quiet = false, techniqueImages = false;
};

// The local farm, then (Markov chains) the summary that `--in-process` prints, read back from the image's
// metadata; the seconds are the farm's wall time, startup and bootstrap included.
void renderWithLocalFarmAndReport(const LocalRenderOptions& lo, int workers, const std::string& farmDir) {
  const auto start = std::chrono::steady_clock::now();
  const ExrImage image = renderWithLocalFarm(lo, workers, farmDir);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!isMarkovChainMethod(lo.settings.method) || lo.outExr.empty()) return;
  const ChainReport report = chainReportFromMetadata(image.metadata);
  if (lo.showProgress)
    std::fputs(formatChainSummary(report, -1, seconds, " (local farm wall time, startup and bootstrap included)")
                   .c_str(), stderr);
  std::fputs(chainWarnings(report).c_str(), stderr);
}

CommandRun setupRender(CLI::App& sub) {
  auto o = std::make_shared<RenderCliOptions>();
  sub.add_option("scene", o->scene, "Scene file (Mitsuba 0.6 / 3.x XML subset)")->required();  // existence is checked by the loader (exit code 2)
  sub.add_option("-o,--output", o->out, "Output EXR; a PNG preview is written next to it (same stem)")->required();
  sub.add_option("--png", o->png, "PNG preview path (default: OUT with the extension .png)");
  const RenderSettingsOptions* settings = &addRenderSettingsOptions(sub);  // owned by `sub`
  sub.add_option("--time", o->time,
                 "Time budget in seconds. pt/lt/bdpt: run work units (in index order) until the time is up "
                 "and develop with the samples actually taken (without --spp: up to 65536 spp, one sample "
                 "per unit; a unit in progress always finishes). Markov chains: bootstrap, measure the "
                 "mutation throughput in a short trial (~7% of the budget, discarded), then choose "
                 "--mutations-per-pixel to fill the rest and run every chain; the chosen value is printed "
                 "and stored in the EXR (mutationsPerPixel): rendering with it reproduces the image exactly")
      ->check(CLI::NonNegativeNumber);
  sub.add_option("-t,--threads", o->threads, "Threads (default: every core)")->check(CLI::NonNegativeNumber);
  sub.add_option("--exposure", o->exposure, "PNG exposure in stops (the EXR is never scaled)")->capture_default_str();
  sub.add_flag("--in-process,!--farm", o->inProcess,
               "Render in this process instead of the local farm (a coordinator and worker processes on "
               "loopback, the default). --time and --technique-images always render in-process");
  sub.add_option("-w,--workers", o->workers,
                 "Local farm: worker processes, sharing --threads (default: one worker process with every thread)")
      ->check(CLI::NonNegativeNumber);
  sub.add_option("--farm-dir", o->farmDir,
                 "Local farm: keep its state (coordinator and worker logs, job database, films) in this "
                 "directory instead of a temporary one removed when the job succeeds");
  sub.add_flag("--technique-images", o->techniqueImages,
               "bdpt: also write OUT_s<s>_t<t>.exr/.png, one image per technique (s light vertices, t camera "
               "vertices), MIS-weighted so that they sum to the full image");
  sub.add_flag("-q,--quiet", o->quiet, "No progress bar, summary or log lines (warnings and errors still show)");

  return [o, settings]() -> int {
    const CommandLineSettings given = settings->settings();
    LocalRenderOptions lo;
    lo.scenePath = o->scene;
    lo.defines = given.defines;
    lo.settings = given.settings;
    lo.settings.timeBudgetSeconds = o->time;
    if (given.hasMaxDepth) lo.maxDepth = given.settings.integrator.maxDepth;
    if (given.hasRrDepth) lo.rrDepth = given.settings.integrator.rrDepth;
    lo.sppGiven = given.hasSpp;
    lo.threads = o->threads;
    lo.outExr = o->out;
    lo.outPng = o->png;
    lo.exposureStops = o->exposure;
    lo.showProgress = !o->quiet;
    if (o->quiet) spdlog::set_level(spdlog::level::warn);  // -q: no bootstrap log lines either (as `eval -q`)
    lo.techniqueImages = o->techniqueImages;
    if (!o->inProcess && o->time == 0 && !lo.techniqueImages)
      renderWithLocalFarmAndReport(lo, o->workers, o->farmDir);
    else if (!o->farmDir.empty())
      throw std::invalid_argument("--farm-dir is for the local farm; this render runs in-process");
    else
      renderLocal(lo);
    return 0;
  };
}

const CommandRegistration kRender("render", "Render a scene to OUT.exr and OUT.png", setupRender);

}  // namespace
}  // namespace mlt::cli
