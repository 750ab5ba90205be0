// The in-process renderer: load a scene, plan the job, run every work unit in this process (TBB), merge
// in unit-index order, develop, write OUT.exr (+ OUT.png). `mltfarm render --in-process` is this
// function; the farm's local mode (coordinator + worker processes) is the other path and must produce the
// same image for the same settings, because both merge the same units in the same order.
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/io/exr_io.h"
#include "common/methods/registry.h"

namespace mlt::cli {

struct LocalRenderOptions {
  std::string scenePath;
  std::map<std::string, std::string> defines;   // Mitsuba -D name=value
  // width/height 0 = the scene's film size. timeBudgetSeconds > 0: pt/lt/bdpt run units until the time
  // is up; Markov chain methods choose mutationsPerPixel to fill the budget and run every chain.
  RenderSettings settings;
  std::optional<int> maxDepth, rrDepth;         // unset: the scene's <integrator> values, else defaults
  bool sppGiven = true;                         // false with a time budget: run until the time is up
  int threads = 0;                              // 0 = every core
  std::string outExr;                           // empty: write nothing
  std::string outPng;                           // empty: OUT.exr with the extension replaced by .png
  float exposureStops = 0;                      // PNG only
  bool showProgress = true;                     // also the summary (b, acceptance, mutations/s) of chains
  // bdpt: also write OUT_s<s>_t<t>.exr per technique (path lengths up to max depth, or 8 if unlimited);
  // the units then run one at a time (each still uses every thread).
  bool techniqueImages = false;
};

// The unit the i-th run of a time budget's throughput trial takes among n planned chains: the base-2
// radical inverse of i scaled to n, so that every prefix of the trial visits chains spread evenly over
// the plan (each of the first 2^j runs in its own 1/2^j of the plan). Chains are planned in order of path
// length (mmlt, rjmlt) and longer paths cost more per mutation, so a trial that took the first chains in
// order measured the cheap ones only: a 4 s budget ran 5.5-5.9 s (mmlt and rjmlt on caustic-mirror and
// door-ajar, one thread; 3.9-4.3 s in this order).
size_t spreadIndex(size_t i, size_t n);

// A Markov chain render with a time budget: the throughput trial and the mutations per pixel it chose.
struct ChainBudgetReport {
  double trialSeconds = 0;
  uint64_t trialMutations = 0;
  double mutationsPerSecond = 0;  // measured by the trial, on every thread
  double mutationsPerPixel = 0;   // chosen; `--mutations-per-pixel` with it reproduces the image exactly
};

struct LocalRenderResult {
  JobPlan plan;                // the plan developed (time budget, pt/lt/bdpt: only the units that ran)
  PartialResult merged;
  std::vector<Color> image;    // developed linear RGB
  ImageMetadata metadata;
  std::string sceneHash;
  double seconds = 0;          // wall time of planning + rendering (not loading or writing)
  double runSeconds = 0;       // wall time of running the work units (after planning)
  std::optional<ChainBudgetReport> chainBudget;  // Markov chains with a time budget
};

LocalRenderResult renderLocal(const LocalRenderOptions& options);

// "out.exr" -> "out.png" (any extension replaced; none added if missing).
std::string pngPathFor(const std::string& exrPath);

}  // namespace mlt::cli
