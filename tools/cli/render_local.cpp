// The in-process renderer (see render_local.h).
#include "tools/cli/render_local.h"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_pipeline.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "common/integrators/evaluators.h"
#include "common/io/png_io.h"
#include "common/job/sample_job.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"
#include "common/scene/scene_hash.h"
#include "tools/cli/progress.h"

namespace mlt::cli {

namespace {

using Clock = std::chrono::steady_clock;

// Without --spp, a time-limited pt/lt/bdpt render plans this many samples per pixel in units of one
// sample each and stops when the time is up.
constexpr int kTimeOnlySppCap = 1 << 16;

// OUT_s<s>_t<t>.exr (+ .png) for every technique, developed with the full image's splat scale P / N.
void writeTechniqueImages(const std::string& outExr, const TechniqueFilms& techniques,
                          const LocalRenderResult& result, float exposureStops) {
  const std::filesystem::path out(outExr);
  const double P = double(result.merged.film.pixelCount()), N = double(result.merged.samples);
  for (int L = 1; L <= techniques.maxLength; ++L) {
    for (int s = 0; s <= L; ++s) {
      const int t = L + 1 - s;
      const Film& film = techniques.films[size_t(TechniqueFilms::index(s, t))];
      std::filesystem::path path = out;
      path.replace_filename(out.stem().string() + "_s" + std::to_string(s) + "_t" + std::to_string(t) + ".exr");
      ImageMetadata m = result.metadata;
      m.numbers["techniqueS"] = s;
      m.numbers["techniqueT"] = t;
      const std::vector<Color> img = film.develop(N > 0 ? P / N : 0.0);
      writeExr(path.string(), film.width(), film.height(), img, m);
      path.replace_extension(".png");
      writePng(path.string(), film.width(), film.height(), img, exposureStops);
    }
  }
}

}  // namespace

std::string pngPathFor(const std::string& exrPath) {
  std::filesystem::path p(exrPath);
  p.replace_extension(".png");
  return p.string();
}

LocalRenderResult renderLocal(const LocalRenderOptions& options) {
  // Fail before rendering, not after, when the output cannot be written.
  if (!options.outExr.empty()) {
    const std::filesystem::path dir = std::filesystem::absolute(options.outExr).parent_path();
    if (!std::filesystem::is_directory(dir))
      throw std::runtime_error(options.outExr + ": output directory " + dir.string() + " does not exist");
  }
  // ---- Scene ----------------------------------------------------------------------------------------
  SceneDesc desc = loadMitsubaScene(options.scenePath, options.defines);
  for (const std::string& w : desc.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  RenderSettings settings = options.settings;
  if (settings.width < 0 || settings.height < 0) throw std::invalid_argument("--width/--height must be positive");
  if (settings.width > 0) desc.camera.width = settings.width;
  if (settings.height > 0) desc.camera.height = settings.height;
  settings.width = settings.height = 0;  // resolved by planJob from the camera
  settings.integrator.maxDepth = options.maxDepth.value_or(desc.maxDepth.value_or(settings.integrator.maxDepth));
  settings.integrator.rrDepth = options.rrDepth.value_or(desc.rrDepth.value_or(settings.integrator.rrDepth));
  const bool timed = settings.timeBudgetSeconds > 0;
  // Without --spp: the scene's sampler sample_count, if it has one (and no time budget was given).
  if (!options.sppGiven && !timed && desc.sampleCount) settings.spp = *desc.sampleCount;
  if (timed && !options.sppGiven && !isMarkovChainMethod(settings.method)) {
    settings.spp = kTimeOnlySppCap;
    if (settings.samplesPerUnit == 0) settings.samplesPerUnit = 1;
  }
  LocalRenderResult result;
  result.sceneHash = sceneContentHash(desc);  // SHA-256 over the scene file and every file it reads
  const std::unique_ptr<RenderScene> scene = RenderScene::build(desc);

  // ---- Plan and run ---------------------------------------------------------------------------------
  const int threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  tbb::global_control threadLimit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  const auto start = Clock::now();
  result.plan = planJob(*scene, settings);
  JobPlan& plan = result.plan;
  const size_t nUnits = plan.units.size();
  std::unique_ptr<ProgressBar> progress;
  if (options.showProgress)
    progress = std::make_unique<ProgressBar>(std::string("render ") + methodName(settings.method), nUnits,
                                             settings.timeBudgetSeconds);

  // Units flow through a pipeline: issued in index order (stopping when the time is up), run in
  // parallel, merged strictly in index order, so the sums do not depend on the thread count.
  const auto deadline = start + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(settings.timeBudgetSeconds));
  size_t nextUnit = 0, merged = 0;
  const RenderScene& sceneRef = *scene;
  std::unique_ptr<TechniqueFilms> techniques;
  std::unique_ptr<PathEvaluator> techniqueEvaluator;
  if (options.techniqueImages) {
    if (plan.settings.method != Method::BDPT) throw std::invalid_argument("--technique-images needs --method bdpt");
    const int maxLength = plan.settings.integrator.maxDepth >= 1 ? plan.settings.integrator.maxDepth : 8;
    techniques = std::make_unique<TechniqueFilms>(maxLength, plan.settings.width, plan.settings.height);
    techniqueEvaluator = makeEvaluator(sceneRef, Method::BDPT, plan.settings.integrator);
  }
  auto runUnit = [&](size_t i) {
    if (techniques) return runSampleUnit(*techniqueEvaluator, plan, plan.units[i], techniques.get());
    return runWorkUnit(sceneRef, plan, plan.units[i]);
  };
  tbb::parallel_pipeline(
      techniques ? 1 : size_t(2 * threads),  // technique films are shared: one unit at a time
      tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                     [&](tbb::flow_control& fc) -> size_t {
                                       if (nextUnit >= nUnits || (timed && Clock::now() >= deadline)) {
                                         fc.stop();
                                         return 0;
                                       }
                                       return nextUnit++;
                                     }) &
          tbb::make_filter<size_t, std::shared_ptr<PartialResult>>(
              tbb::filter_mode::parallel,
              [&](size_t i) { return std::make_shared<PartialResult>(runUnit(i)); }) &
          tbb::make_filter<std::shared_ptr<PartialResult>, void>(tbb::filter_mode::serial_in_order,
                                                                 [&](std::shared_ptr<PartialResult> r) {
                                                                   result.merged.add(*r);
                                                                   ++merged;
                                                                   if (progress) progress->update(merged);
                                                                 }));
  if (merged == 0) throw std::runtime_error("no work unit finished within the time budget");
  // A time budget ran out: pt/lt/bdpt develop with the samples the merged result holds (sample_job.cpp).
  // Markov chains keep the full plan; developImage sees fewer mutations than planned and normalizes by
  // the mutations merged (a chain subset of a stationary chain set; see mlt_job.cpp).
  if (merged < nUnits && !isMarkovChainMethod(plan.settings.method)) plan.units.resize(merged);
  result.image = developImage(plan, result.merged);
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();

  // ---- Metadata and output --------------------------------------------------------------------------
  const bool chains = isMarkovChainMethod(plan.settings.method);
  const double pixels = double(result.merged.film.pixelCount());
  ImageMetadata& m = result.metadata;
  m.strings["software"] = "mltfarm";
  m.strings["method"] = methodName(plan.settings.method);
  m.strings["scene"] = options.scenePath;
  m.strings["sceneHash"] = result.sceneHash;
  m.strings["seed"] = std::to_string(plan.settings.seed);  // a string: 64-bit seeds do not fit a double
  m.numbers["width"] = plan.settings.width;
  m.numbers["height"] = plan.settings.height;
  m.numbers["maxDepth"] = plan.settings.integrator.maxDepth;
  m.numbers["rrDepth"] = plan.settings.integrator.rrDepth;
  m.numbers["renderSeconds"] = result.seconds;
  m.numbers["threads"] = threads;
  m.numbers["workUnits"] = double(merged);
  m.numbers["workUnitsPlanned"] = double(nUnits);
  m.numbers["nonFiniteSamples"] = double(result.merged.film.nonFiniteSamples());
  if (timed) m.numbers["timeBudgetSeconds"] = plan.settings.timeBudgetSeconds;
  if (chains) {
    m.numbers["mutations"] = double(result.merged.samples);
    m.numbers["mutationsPerPixel"] = double(result.merged.samples) / pixels;
    m.numbers["chains"] = double(merged);
    m.numbers["b"] = plan.norm.b;
    m.numbers["bStdErr"] = plan.norm.bStdErr;
    m.numbers["bootstrapSamples"] = double(plan.norm.bootstrapSamples);
    m.numbers["largeStepProb"] = plan.settings.largeStepProb;
    for (size_t k = 0; k < plan.norm.bk.size(); ++k)
      if (plan.norm.bk[k] != 0) m.numbers["b" + std::to_string(k)] = plan.norm.bk[k];
  } else {
    m.numbers["samples"] = double(result.merged.samples);
    m.numbers["spp"] = double(result.merged.samples) / pixels;
  }
  if (!options.outExr.empty()) {
    writeExr(options.outExr, plan.settings.width, plan.settings.height, result.image, m);
    const std::string png = options.outPng.empty() ? pngPathFor(options.outExr) : options.outPng;
    writePng(png, plan.settings.width, plan.settings.height, result.image, options.exposureStops);
    if (techniques) writeTechniqueImages(options.outExr, *techniques, result, options.exposureStops);
  }
  if (progress) {
    const char* what = chains ? "mutations" : "samples";
    char line[512];
    std::snprintf(line, sizeof line, "%s: %llu %s in %.2f s (%.3g %s/s), %zu/%zu work units%s%s",
                  methodName(plan.settings.method), (unsigned long long)result.merged.samples, what, result.seconds,
                  double(result.merged.samples) / std::max(result.seconds, 1e-9), what, merged, nUnits,
                  result.merged.film.nonFiniteSamples() ? ", non-finite samples dropped: " : "",
                  result.merged.film.nonFiniteSamples()
                      ? std::to_string(result.merged.film.nonFiniteSamples()).c_str()
                      : "");
    progress->finish(line);
  }
  return result;
}

}  // namespace mlt::cli
