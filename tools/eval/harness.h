// The accuracy-against-speed harness behind `mltfarm eval`: scenes x methods x budgets x R runs, each
// run a complete render job with its own job seed, measured against a reference (see reference.h),
// analysed for stability (stability.h) and written out (runs.csv, acceptance.csv, refs.csv, error maps,
// summary.md; charts by tools/eval/charts.py).
//
// Budgets. Equal time (default): budgets are seconds. A short calibration per (scene, method) fits
// time(work) = F + c * work (F = fixed cost such as the bootstrap, work = spp or mutations per pixel) from
// a minimal job and a growing one (see evalMethod); each run then asks for work = (budget - F) / c, and c
// is refined (least squares) from every
// run. The run is a complete job (every planned chain runs, so the estimator is exactly what users run)
// and the real wall time is recorded next to the budget. Equal samples (--equal-samples): budgets are spp
// for pt/lt/bdpt and mutations per pixel for the Markov chain methods.
#pragma once
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/methods/registry.h"
#include "common/scene/scene_desc.h"
#include "tools/eval/reference.h"
#include "tools/eval/run_record.h"
#include "tools/eval/stability.h"

namespace mlt::eval {

// "[label=]method[+separate-direct|+direct-in-chains][+mis-balance|+mis-power][+name:value]...[*scale]": e.g. "pt", "mmlt",
// "mmlt-sd=mmlt+separate-direct", "mmlt-lum=mmlt+target:luminance" (a method parameter, RenderMethod::params,
// as --name value would set it), "pt-biased=pt*1.05". +separate-direct: the method renders the direct
// light by a pt pass (RenderSettings::directLight Separate, the direct pass sized by the plan: directSppFor);
// +direct-in-chains: by its chains (Chains); without either the plan decides (Auto, direct_light_rule.h).
// Both are refused for a method that cannot render the direct light apart. +mis-balance / +mis-power: the
// MIS heuristic (IntegratorSettings::heuristic, --mis-heuristic); without either, the harness's base. A scale other than 1
// multiplies every developed image of the method: a test hook for a deliberately biased method.
struct MethodSpec {
  std::string label;
  std::string method = "pt";
  DirectLight directLight = DirectLight::Auto;
  std::optional<MisHeuristic> heuristic;
  double testScale = 1.0;
  MethodParams params;  // the method's own parameters (checked by the method)
};
MethodSpec parseMethodSpec(const std::string& spec);  // throws std::invalid_argument naming the spec

struct EvalScene {
  std::string name;   // short, file-name safe (the scene file's stem)
  SceneDesc desc;     // as loaded; the harness applies the size override
};

// Test hook: run `run` of `method` (at every budget, or only budgetIndex >= 0) gets its error against
// the reference multiplied by `factor`: image = ref + factor * (image - ref) (relMSE x factor^2).
struct OutlierInjection {
  std::string method;
  int budgetIndex = -1;
  int run = 0;
  double factor = 10;
};

// One job rendered through the farm (coordinator + workers). Set by the CLI (the library does not link
// gRPC). seconds: the wall time from submission to the developed image.
struct FarmRunResult {
  std::vector<Color> image;
  double seconds = 0;
  uint64_t samples = 0;
  ChainStats stats;
  int units = 0;
};
using FarmRunner = std::function<FarmRunResult(const EvalScene& scene, const RenderSettings& settings)>;

struct EvalConfig {
  std::vector<EvalScene> scenes;
  std::vector<MethodSpec> methods;
  int runs = 3;
  std::vector<double> budgets;          // seconds, or spp / mutations per pixel with equalSamples
  bool equalSamples = false;
  RenderSettings base;                  // width/height (0 = the scene's), depth, chain parameters
  bool depthFromScene = true;           // use the scene's <integrator> maxDepth/rrDepth when given
  double eps = 1e-2;                    // relMSE epsilon
  uint64_t seed = 1;
  int threads = 0;                      // 0 = every core
  std::string outDir;
  std::string userReference;            // an EXR (only with one scene); empty = render one
  ReferenceSettings reference;
  bool cacheReferences = true;          // under outDir/refs
  FarmRunner farm;                      // set: every run goes through the farm (mode "farm")
  std::optional<OutlierInjection> injectOutlier;
  StabilityConfig stability;
  bool errorMaps = true;
  bool charts = true;                   // run the chart script after writing the tables
  std::string python = "/usr/bin/python3";
  std::string chartScript;              // empty: <source dir>/tools/eval/charts.py
  std::string commandLine;              // for the summary
  bool verbose = true;                  // progress lines on stderr
};

// The fitted time model of one (scene, method) in equal-time mode: seconds = fixed + perWork * work.
struct Calibration {
  std::string scene, method;
  double fixedSeconds = 0;   // bootstrap, planning, thread start-up: paid by every run whatever its budget
  double perWork = 0;        // seconds per spp (sample methods) or per mutation per pixel (chains)
};

// A method that could not run on a scene at all (e.g. it rejects the scene's settings): reported, and the
// evaluation goes on with the other methods.
struct MethodFailure {
  std::string scene, method, error;
};

struct EvalResult {
  std::vector<MethodFailure> failures;
  std::vector<Calibration> calibrations;  // empty with equal samples
  std::vector<RunRecord> runs;
  std::vector<ReferenceInfo> refs;
  StabilityReport stability;
};

EvalResult runEval(const EvalConfig& config);

// Writes runs.csv, acceptance.csv, refs.csv and summary.md under outDir (used by runEval after each
// scene, so an interrupted evaluation keeps what it measured).
void writeEvalOutputs(const EvalConfig& config, EvalResult& result);

// Per-run job seed: a pure function of (base seed, scene, method label, budget index, run).
uint64_t runSeed(uint64_t baseSeed, const std::string& scene, const std::string& method, int budgetIndex, int run);

}  // namespace mlt::eval
