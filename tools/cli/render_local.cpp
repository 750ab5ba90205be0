// The in-process renderer (see render_local.h).
#include "tools/cli/render_local.h"

#include "common/job/executor.h"
#include "common/methods/image_metadata.h"

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <spdlog/spdlog.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "common/integrators/evaluators.h"
#include "common/io/png_io.h"
#include "common/methods/pss_method.h"
#include "common/methods/registry.h"
#include "common/job/sample_job.h"
#include "common/methods/chain_report.h"
#include "common/render/render_scene.h"
#include "common/scene/scene_loader.h"
#include "common/scene/scene_hash.h"
#include "tools/cli/progress.h"

namespace mlt::cli {

namespace {

using Clock = std::chrono::steady_clock;

// Without --spp, a time-limited pt/lt/bdpt render plans this many samples per pixel in units of one
// sample each and stops when the time is up.
constexpr int kTimeOnlySppCap = 1 << 16;

// Time-budgeted Markov chains (see planChainsForTimeBudget).
constexpr double kTrialShare = 0.07;          // share of the budget spent measuring mutation throughput,
constexpr double kTrialMaxSeconds = 1.0;      // at most this long (a longer trial measures no better)
constexpr uint64_t kTrialUnitMutations = 8192;  // a trial unit: this long a prefix of a planned chain
constexpr double kBudgetFill = 0.95;          // share of the remaining budget planned (develop, write, tail)
constexpr int kMutationsPerPixelDigits = 3;   // the chosen mutations per pixel, rounded down to this many

// The one executor (common/job/executor.h): units issued in order while next(i) says so, run in
// parallel, merged strictly in index order.
template <class Next, class Run, class Merge>
void runPipeline(size_t tokens, Next next, Run run, Merge merge) {
  UnitExecution e;
  e.parallelism = tokens;
  e.issue = next;
  e.run = run;
  e.merge = [&](size_t i, PartialResult& r) { merge(i, r); };
  executeUnits(e);
}

// x rounded down to `digits` significant decimal digits, returned as the double that this decimal reads
// as (so that typing the printed value reproduces it exactly).
double roundDownSignificant(double x, int digits) {
  if (!(x > 0) || !std::isfinite(x)) return 0;
  const double q = std::pow(10.0, std::floor(std::log10(x)) - (digits - 1));
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, std::floor(x / q * (1 + 1e-12)) * q);
  return std::strtod(buf, nullptr);
}

// A time budget for a Markov chain method. The image must stay a pure function of (settings, seed,
// mutations per pixel), so no chain is cut short or dropped; instead:
//   1. bootstrap once, sized to its share of the budget (a pure function of the seed and settings with the
//      bootstrap size resolved, independent of the mutation count);
//   2. measure mutation throughput on every thread with prefixes of the planned chains, for about
//      kTrialShare of the budget, at most kTrialMaxSeconds (their results are discarded: the trial never
//      touches the image);
//   3. choose mutations per pixel to fill what remains of the budget (rounded down to 3 digits; less the
//      estimated time of a direct pass), plan again from the same bootstrap, and run every
//      chain of that plan.
// `--mutations-per-pixel` with the chosen value renders the same image, bit for bit, without a budget.
JobPlan planChainsForTimeBudget(const RenderScene& scene, RenderSettings s, Clock::time_point start, int threads,
                                ChainBudgetReport& report) {
  s.width = scene.camera().width();  // resolved as planJob does
  s.height = scene.camera().height();
  const double budget = s.timeBudgetSeconds;
  // 1. The bootstrap gets kBootstrapShare of the budget (mlt_job.h): a probe of the smallest automatic size
  //    measures the candidates' throughput, and the count that fits in what the probe left of that share
  //    is resolved into the settings (and recorded in the image, so that --bootstrap with it reproduces
  //    the image without a budget). The probe is part of the share: probe + bootstrap ~ kBootstrapShare,
  //    or the probe alone when it took the whole share (short budgets, expensive candidates).
  const ChainJobSpec* method = findChainJobSpec(s.method);
  if (!method) throw std::invalid_argument("--time: method " + s.method + " has no time-budgeted planning yet");
  MarkovChainBootstrap boot;
  if (s.bootstrapSamples == 0) {
    RenderSettings probe = s;
    probe.bootstrapSamples = int(kMinBootstrapPerLength);
    boot = bootstrapMarkovChainJob(scene, probe);
    const double probeSeconds = boot.result.seconds;
    // Its throughput in the unit of --bootstrap, the cost of one of the chains' mutations (bootstrap.h,
    // chainMixCost): the probe's cost (numbers drawn) per second over that cost. b_1's camera rays (mmlt,
    // rjmlt) cost the same at any size: left out of the throughput; the bootstrap's budget counts them
    // itself (BootstrapConfig::spentCost), so what is left of the share is all the bootstrap's.
    const double candidateSeconds = probeSeconds - boot.raySeconds - (boot.pilot ? boot.pilot->seconds : 0.0);
    const double perSecond =
        bootstrapCost(boot.result.lengths) / std::max(candidateSeconds, 1e-6) / chainMixCost(boot.result.lengths);
    const double shareLeft = std::max(0.0, kBootstrapShare * budget - probeSeconds);
    // The final bootstrap reuses the probe's rays (the same estimate: bootstrapMarkovChainJob's `earlier`)
    // but still charges them to its budget, so that the size resolved here reproduces the image without a
    // budget: the probe already paid their time, so their cost is added back for the candidates (when any
    // of the share is left: otherwise the probe is the bootstrap).
    const double rayMutations = boot.emission && shareLeft > 0
                                    ? double(boot.emission->rays) * kEmissionRayCost / chainMixCost(boot.result.lengths)
                                    : 0.0;
    // Sized for the lengths of the probe's choice of direct light (--direct-light auto).
    s.bootstrapSamples = int(bootstrapPerLengthFor(*method, withDirectLightChoice(s, boot.settings.directLight),
                                                   shareLeft * perSecond + rayMutations));
    if (uint64_t(s.bootstrapSamples) != kMinBootstrapPerLength) {
      const MarkovChainBootstrap probed = std::move(boot);
      boot = bootstrapMarkovChainJob(scene, s, &probed);
      boot.result.seconds += probeSeconds;
      boot.raySeconds = probed.raySeconds;
    }
  } else {
    boot = bootstrapMarkovChainJob(scene, s);
  }
  JobPlan trialPlan = planMarkovChainJob(scene, s, boot);
  std::vector<WorkUnit> trialUnits, directUnits;
  for (const WorkUnit& u : trialPlan.units) {
    if (u.mutations == 0) {
      directUnits.push_back(u);  // the direct pass: pt sample batches, whose cost does not depend on M
      continue;
    }
    trialUnits.push_back(u);
    trialUnits.back().mutations = std::min(u.mutations, kTrialUnitMutations);
  }
  // b = 0: no chains to run, whatever the budget; unless the method plans such a job otherwise (veach-mlt
  // without its light-view pass, which its chains carry: veach_job.h), it is black.
  if (trialUnits.empty()) {
    const std::optional<RenderSettings> again = method->settingsWhenNoChains(s);
    return again ? findMethod(s.method).plan(scene, *again) : trialPlan;
  }

  // The direct pass (directLight Separate) takes its share of the budget first: one of its units, timed. Sized
  // by the plan (spp 0: directSppFor), it grows with the mutations per pixel, so its time per mutation per
  // pixel joins the chains' in step 3 instead.
  double directSeconds = 0, directSecondsPerMpp = 0;
  if (!directUnits.empty()) {
    const auto t0 = Clock::now();
    runWorkUnit(scene, trialPlan, directUnits.front());
    directSeconds = std::chrono::duration<double>(Clock::now() - t0).count() * double(directUnits.size()) /
                    double(std::max(threads, 1));
    if (s.spp == 0 || s.directLight == DirectLight::Auto) {  // sized by the plan: grows with the mutations
      directSecondsPerMpp = directSeconds / double(trialPlan.settings.spp) *
                            directSppPerMutation(*method, trialPlan.settings, boot.pilot ? &*boot.pilot : nullptr);
      directSeconds = 0;
    }
  }

  // 2. Throughput trial.
  const auto trialStart = Clock::now();
  const auto trialEnd = trialStart + std::chrono::duration_cast<Clock::duration>(
                                         std::chrono::duration<double>(std::min(kTrialShare * budget, kTrialMaxSeconds)));
  uint64_t trialMutations = 0;
  runPipeline(
      unitsInFlight(size_t(threads)),
      [&](size_t i) { return i < size_t(threads) || Clock::now() < trialEnd; },
      [&](size_t i) { return runWorkUnit(scene, trialPlan, trialUnits[spreadIndex(i, trialUnits.size())]); },
      [&](size_t, const PartialResult& r) { trialMutations += r.samples; });
  report.trialSeconds = std::chrono::duration<double>(Clock::now() - trialStart).count();
  report.trialMutations = trialMutations;
  // Wall-time throughput: it includes the trial's ramp-up and drain (so it errs low, by ~10% here), but
  // also whatever share of the cores other processes take, which per-unit busy time would not see.
  report.mutationsPerSecond = double(trialMutations) / std::max(report.trialSeconds, 1e-9);

  // 3. Fill the rest of the budget.
  double remaining = budget - std::chrono::duration<double>(Clock::now() - start).count() - directSeconds;
  if (remaining < report.trialSeconds) {
    std::fprintf(stderr, "warning: bootstrap, throughput trial (and direct pass) take %.2f s of the %.2f s "
                 "budget; the chains get %.2f s more (increase --time or decrease --bootstrap)\n",
                 budget - remaining, budget, report.trialSeconds);
    remaining = report.trialSeconds;
  }
  const double P = double(s.width) * double(s.height);
  const double secondsPerMpp = P / std::max(report.mutationsPerSecond, 1e-9) + directSecondsPerMpp;
  const double mpp = roundDownSignificant(kBudgetFill * remaining / secondsPerMpp, kMutationsPerPixelDigits);
  s.mutationsPerPixel = std::max(mpp, 1.0 / P);  // at least one mutation
  report.mutationsPerPixel = s.mutationsPerPixel;
  return planMarkovChainJob(scene, s, boot);
}

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

size_t spreadIndex(size_t i, size_t n) {
  uint64_t v = uint64_t(i), r = 0;
  for (int b = 0; b < 64; ++b, v >>= 1) r = (r << 1) | (v & 1);  // bit reversal: r / 2^64 in [0, 1)
  // The first unit at or after r / 2^64 of the plan, ceil(r n / 2^64), in exact integer arithmetic.
  const unsigned __int128 x = static_cast<unsigned __int128>(r) * n;
  const uint64_t u = uint64_t(x >> 64) + (uint64_t(x) != 0 ? 1 : 0);
  return size_t(std::min<uint64_t>(u, n - 1));
}

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
  SceneDesc desc = loadScene(options.scenePath, options.defines);
  for (const std::string& w : desc.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  RenderSettings settings = options.settings;
  if (settings.width < 0 || settings.height < 0) throw std::invalid_argument("--width/--height must be positive");
  if (settings.width > 0) desc.camera.width = settings.width;
  if (settings.height > 0) desc.camera.height = settings.height;
  settings.width = settings.height = 0;  // resolved by planJob from the camera
  settings.integrator.maxDepth = options.maxDepth.value_or(desc.maxDepth.value_or(settings.integrator.maxDepth));
  settings.integrator.rrDepth = options.rrDepth.value_or(desc.rrDepth.value_or(settings.integrator.rrDepth));
  const bool timed = settings.timeBudgetSeconds > 0;
  if (desc.sampleCount && takesSceneSampleCount(settings, options.sppGiven)) settings.spp = *desc.sampleCount;
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
  const bool chains = isMarkovChainMethod(settings.method);
  if (timed && chains) {
    result.chainBudget.emplace();
    result.plan = planChainsForTimeBudget(*scene, settings, start, threads, *result.chainBudget);
  } else {
    result.plan = planJob(*scene, settings);
  }
  JobPlan& plan = result.plan;
  const size_t nUnits = plan.units.size();
  // A crowded start (chain_report.h) is known now; the summary's warning repeats it after the render.
  if (chains)
    if (const std::string crowded = describeCrowdedStart(crowdedStart(plan)); !crowded.empty())
      spdlog::warn("{}: {}", settings.method, crowded);
  std::unique_ptr<ProgressBar> progress;
  if (options.showProgress)
    progress = std::make_unique<ProgressBar>(std::string("render ") + settings.method, nUnits,
                                             chains ? 0.0 : settings.timeBudgetSeconds);

  // Units are issued in index order (pt/lt/bdpt with a time budget: until the time is up; Markov chains
  // always run every planned chain), run in parallel, merged strictly in index order.
  const auto deadline = start + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(settings.timeBudgetSeconds));
  const bool stopAtDeadline = timed && !chains;
  size_t merged = 0;
  const RenderScene& sceneRef = *scene;
  std::unique_ptr<TechniqueFilms> techniques;
  std::unique_ptr<PathEvaluator> techniqueEvaluator;
  if (options.techniqueImages) {
    if (plan.settings.method != "bdpt") throw std::invalid_argument("--technique-images needs --method bdpt");
    const int maxLength = plan.settings.integrator.maxDepth >= 1 ? plan.settings.integrator.maxDepth : 8;
    techniques = std::make_unique<TechniqueFilms>(maxLength, plan.settings.width, plan.settings.height);
    techniqueEvaluator = makeEvaluator(sceneRef, "bdpt", plan.settings.integrator);
  }
  const auto runStart = Clock::now();
  runPipeline(
      techniques ? 1 : unitsInFlight(size_t(threads)),  // technique films are shared: one unit at a time
      [&](size_t i) { return i < nUnits && !(stopAtDeadline && Clock::now() >= deadline); },
      [&](size_t i) {
        if (techniques) return runSampleUnit(*techniqueEvaluator, plan, plan.units[i], techniques.get());
        return runWorkUnit(sceneRef, plan, plan.units[i]);
      },
      [&](size_t, const PartialResult& r) {
        result.merged.add(r);
        ++merged;
        if (progress) progress->update(merged);
      });
  if (merged == 0 && nUnits > 0) throw std::runtime_error("no work unit finished within the time budget");
  // A time budget ran out: pt/lt/bdpt develop with the samples the merged result holds (sample_job.cpp).
  if (merged < nUnits) plan.units.resize(merged);
  result.runSeconds = std::chrono::duration<double>(Clock::now() - runStart).count();
  result.image = developImage(plan, result.merged);
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();

  // ---- Metadata and output --------------------------------------------------------------------------
  result.metadata = imageMetadata(plan, result.merged, options.scenePath, result.sceneHash);
  ImageMetadata& m = result.metadata;
  m.numbers["workUnitsPlanned"] = double(nUnits);  // plan.units was cut to the units a time budget ran
  m.numbers["renderSeconds"] = result.seconds;
  m.numbers["threads"] = threads;
  if (timed) m.numbers["timeBudgetSeconds"] = plan.settings.timeBudgetSeconds;
  std::optional<ChainReport> report;
  if (chains) {
    report = makeChainReport(plan, result.merged);
    addMoveSecondsMetadata(*report, m);  // wall time per move kind (chain.h)
    m.numbers["bootstrapSeconds"] = plan.norm.bootstrapSeconds;
    m.numbers["chainSeconds"] = result.runSeconds;
    m.numbers["mutationsPerSecond"] = double(result.merged.samples) / std::max(result.runSeconds, 1e-9);
    if (result.chainBudget) {
      m.numbers["trialSeconds"] = result.chainBudget->trialSeconds;
      m.numbers["trialMutations"] = double(result.chainBudget->trialMutations);
    }
  }
  if (!options.outExr.empty()) {
    writeExr(options.outExr, plan.settings.width, plan.settings.height, result.image, m);
    const std::string png = options.outPng.empty() ? pngPathFor(options.outExr) : options.outPng;
    writePng(png, plan.settings.width, plan.settings.height, result.image, options.exposureStops);
    if (techniques) writeTechniqueImages(options.outExr, *techniques, result, options.exposureStops);
  }
  const uint64_t nonFinite = result.merged.film.nonFiniteSamples();
  const std::string nonFiniteNote = nonFinite ? ", non-finite samples dropped: " + std::to_string(nonFinite) : "";
  if (progress && chains) {
    const std::string trialNote =
        result.chainBudget ? fmt::format(", throughput trial {:.2f} s", result.chainBudget->trialSeconds) : "";
    progress->finish(fmt::format("{}: {}/{} work units in {:.2f} s (bootstrap {:.2f} s = {:.1f}% of the job{}){}",
                                 plan.settings.method, merged, nUnits, result.seconds,
                                 plan.norm.bootstrapSeconds,
                                 100 * plan.norm.bootstrapSeconds / std::max(result.seconds, 1e-9), trialNote,
                                 nonFiniteNote));
    std::string summary = formatChainSummary(*report, plan.norm.bootstrapSeconds, result.runSeconds);
    if (result.chainBudget)
      summary += fmt::format("time budget {} s: the trial measured {:.4g} mutations/s; chose {} mutations per pixel "
                             "(the same settings with --mutations-per-pixel {} --bootstrap {} instead of --time give the same image)\n",
                             plan.settings.timeBudgetSeconds, result.chainBudget->mutationsPerSecond,
                             result.chainBudget->mutationsPerPixel, result.chainBudget->mutationsPerPixel,
                             plan.settings.bootstrapSamples);
    std::fputs(summary.c_str(), stderr);
  } else if (progress) {
    progress->finish(fmt::format("{}: {} samples in {:.2f} s ({:.3g} samples/s), {}/{} work units{}",
                                 plan.settings.method, result.merged.samples, result.seconds,
                                 double(result.merged.samples) / std::max(result.seconds, 1e-9), merged, nUnits,
                                 nonFiniteNote));
  }
  if (report) std::fputs(chainWarnings(*report).c_str(), stderr);
  return result;
}

}  // namespace mlt::cli
