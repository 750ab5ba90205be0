// `mltfarm render SCENE.xml ... -o OUT.exr`: renders a scene and writes OUT.exr (with metadata) and
// OUT.png. By default through the local farm (a coordinator plus worker processes on loopback,
// tools/cli/farm_render.h); --in-process renders in this process. Both call the same job API.
#include <chrono>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "common/io/exr_io.h"
#include "common/mlt/chain_report.h"
#include "tools/cli/commands.h"
#include "tools/cli/farm_render.h"
#include "tools/cli/render_local.h"

namespace mlt::cli {
namespace {

struct RenderCliOptions {
  std::string scene, out, method = "bdpt", png;
  int spp = 16, samplesPerUnit = 0, threads = 0, width = 0, height = 0, maxDepth = 0, rrDepth = 0;
  double mutationsPerPixel = 16, time = 0;
  int chains = 0, bootstrap = 0;
  float largeStep = 0.3f, exposure = 0;
  std::string kernel = "kelemen", splatting = "expected-value";
  float s1 = 1.0f / 1024, s2 = 1.0f / 64, sigma = 0.01f;
  bool separateDirect = false;
  uint64_t seed = 1;
  std::vector<std::string> defines;
  bool inProcess = false, quiet = false, techniqueImages = false;
  int workers = 0;
};

std::map<std::string, std::string> parseDefines(const std::vector<std::string>& defines) {
  std::map<std::string, std::string> out;
  for (const std::string& d : defines) {
    const size_t eq = d.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument("--define '" + d + "': expected name=value");
    out[d.substr(0, eq)] = d.substr(eq + 1);
  }
  return out;
}

// The local farm, then (Markov chains) the summary that `--in-process` prints, read back from the image's
// metadata; the seconds are the farm's wall time, startup and bootstrap included.
void renderWithLocalFarmAndReport(const LocalRenderOptions& lo, int workers) {
  const auto start = std::chrono::steady_clock::now();
  renderWithLocalFarm(lo, workers);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!isMarkovChainMethod(lo.settings.method) || lo.outExr.empty()) return;
  const ChainReport report = chainReportFromMetadata(readExr(lo.outExr).metadata);
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
  sub.add_option("-m,--method", o->method, "pt | lt | bdpt | pssmlt | pssmlt-bdpt | mmlt")
      ->capture_default_str()
      ->check(CLI::IsMember({"pt", "lt", "bdpt", "pssmlt", "pssmlt-bdpt", "mmlt"}));
  auto* spp = sub.add_option("--spp", o->spp, "Samples per pixel for pt, lt (light paths = spp * pixels) and bdpt (default: the scene's sampler sample_count, else 16)")
                  ->check(CLI::PositiveNumber);
  sub.add_option("--samples-per-unit", o->samplesPerUnit,
                 "pt/lt/bdpt: samples per pixel in one work unit (0 = spp / 16, rounded up)")
      ->check(CLI::NonNegativeNumber);
  sub.add_option("--mutations-per-pixel", o->mutationsPerPixel, "Markov chain methods: mutations per pixel")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub.add_option("--chains", o->chains, "Markov chain methods: number of chains (0 = automatic)")
      ->check(CLI::NonNegativeNumber);
  sub.add_option("--bootstrap", o->bootstrap, "Markov chain methods: bootstrap candidates per path length; 0 = automatic (at most 4% of the mutations or of the time budget; b is refined by the chains' large steps)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sub.add_option("--large-step", o->largeStep, "Markov chain methods: large-step probability")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  sub.add_option("--kernel", o->kernel,
                 "Markov chain methods: small-step kernel, kelemen (exponential, --s1/--s2) or gaussian (--sigma)")
      ->capture_default_str()
      ->check(CLI::IsMember({"kelemen", "gaussian"}));
  sub.add_option("--s1", o->s1, "Kelemen kernel: smallest step")->check(CLI::PositiveNumber);
  sub.add_option("--s2", o->s2, "Kelemen kernel: largest step")->check(CLI::PositiveNumber);
  sub.add_option("--sigma", o->sigma, "Gaussian kernel: standard deviation")->check(CLI::PositiveNumber);
  sub.add_option("--splatting", o->splatting,
                 "Markov chain methods: expected-value (Veach: proposal weighted by a, current state by 1 - a) "
                 "or kelemen-mis (Kelemen et al.'s large-step MIS weights)")
      ->capture_default_str()
      ->check(CLI::IsMember({"expected-value", "kelemen-mis"}));
  sub.add_flag("--separate-direct", o->separateDirect,
               "pssmlt-bdpt, mmlt: render paths of up to 2 segments by bdpt (--spp samples) and let the chains do "
               "only the longer ones (Veach's refinement)");
  sub.add_option("--time", o->time,
                 "Time budget in seconds. pt/lt/bdpt: run work units (in index order) until the time is up "
                 "and develop with the samples actually taken (without --spp: up to 65536 spp, one sample "
                 "per unit; a unit in progress always finishes). Markov chains: bootstrap, measure the "
                 "mutation throughput in a short trial (~7% of the budget, discarded), then choose "
                 "--mutations-per-pixel to fill the rest and run every chain; the chosen value is printed "
                 "and stored in the EXR (mutationsPerPixel): rendering with it reproduces the image exactly")
      ->check(CLI::NonNegativeNumber);
  auto* maxDepth = sub.add_option("--max-depth", o->maxDepth,
                                  "Maximum path length in segments (edges): 1 = directly visible emitters "
                                  "only, 2 = direct lighting, ...; -1 = unlimited (default: the scene's "
                                  "<integrator> max_depth, else 5)")
                       ->check(CLI::Range(-1, 1 << 20));
  auto* rrDepth = sub.add_option("--rr-depth", o->rrDepth,
                                 "Russian roulette starts after this many segments (default: the scene's "
                                 "rr_depth, else 5)")
                      ->check(CLI::NonNegativeNumber);
  sub.add_option("--seed", o->seed, "Job seed (the image is a pure function of the settings and the seed)")
      ->capture_default_str();
  sub.add_option("-t,--threads", o->threads, "Threads (default: every core)")->check(CLI::NonNegativeNumber);
  auto* width = sub.add_option("--width", o->width, "Film width (default: the scene's)")->check(CLI::PositiveNumber);
  auto* height = sub.add_option("--height", o->height, "Film height (default: the scene's)")->check(CLI::PositiveNumber);
  width->needs(height);
  height->needs(width);
  sub.add_option("--exposure", o->exposure, "PNG exposure in stops (the EXR is never scaled)")->capture_default_str();
  sub.add_option("-D,--define", o->defines, "Scene parameter name=value (Mitsuba's -D), repeatable");
  sub.add_flag("--in-process,!--farm", o->inProcess,
               "Render in this process instead of the local farm (a coordinator and worker processes on "
               "loopback, the default). --time and --technique-images always render in-process");
  sub.add_option("-w,--workers", o->workers,
                 "Local farm: worker processes (default: --threads, else every core)")
      ->check(CLI::NonNegativeNumber);
  sub.add_flag("--technique-images", o->techniqueImages,
               "bdpt: also write OUT_s<s>_t<t>.exr/.png, one image per technique (s light vertices, t camera "
               "vertices), MIS-weighted so that they sum to the full image");
  sub.add_flag("-q,--quiet", o->quiet, "No progress bar or summary");

  return [o, spp, maxDepth, rrDepth]() -> int {
    LocalRenderOptions lo;
    lo.scenePath = o->scene;
    lo.defines = parseDefines(o->defines);
    RenderSettings& s = lo.settings;
    s.method = parseMethod(o->method);
    s.seed = o->seed;
    s.width = o->width;
    s.height = o->height;
    s.spp = o->spp;
    s.samplesPerUnit = o->samplesPerUnit;
    s.mutationsPerPixel = o->mutationsPerPixel;
    s.chains = o->chains;
    s.bootstrapSamples = o->bootstrap;
    s.largeStepProb = o->largeStep;
    s.kernel = o->kernel == "gaussian" ? MutationKernel::Gaussian : MutationKernel::Kelemen;
    s.kelemenS1 = o->s1;
    s.kelemenS2 = o->s2;
    s.gaussianSigma = o->sigma;
    s.splatting = o->splatting == "kelemen-mis" ? MltSplatting::KelemenMIS : MltSplatting::ExpectedValue;
    s.separateDirect = o->separateDirect;
    s.timeBudgetSeconds = o->time;
    if (maxDepth->count()) lo.maxDepth = o->maxDepth;
    if (rrDepth->count()) lo.rrDepth = o->rrDepth;
    lo.sppGiven = spp->count() > 0;
    lo.threads = o->threads;
    lo.outExr = o->out;
    lo.outPng = o->png;
    lo.exposureStops = o->exposure;
    lo.showProgress = !o->quiet;
    lo.techniqueImages = o->techniqueImages;
    if (!o->inProcess && s.timeBudgetSeconds == 0 && !lo.techniqueImages)
      renderWithLocalFarmAndReport(lo, o->workers > 0 ? o->workers : o->threads);
    else
      renderLocal(lo);
    return 0;
  };
}

const CommandRegistration kRender("render", "Render a scene to OUT.exr and OUT.png", setupRender);

}  // namespace
}  // namespace mlt::cli
