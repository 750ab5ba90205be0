#include "tools/eval/harness.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "common/core/rng.h"
#include "common/methods/pss_method.h"
#include "common/io/png_io.h"
#include "common/render/render_scene.h"
#include "tools/eval/error_map.h"
#include "tools/eval/bands.h"
#include "tools/eval/ideal_chain.h"
#include "tools/eval/job_runner.h"
#include "tools/eval/report.h"

#ifndef MLTFARM_SOURCE_DIR
#define MLTFARM_SOURCE_DIR "."
#endif

namespace mlt::eval {

namespace fs = std::filesystem;

MethodSpec parseMethodSpec(const std::string& spec) {
  MethodSpec m;
  std::string rest = spec;
  size_t eq = rest.find('=');
  if (eq != std::string::npos) {
    m.label = rest.substr(0, eq);
    rest = rest.substr(eq + 1);
    if (m.label.empty()) throw std::invalid_argument("method spec '" + spec + "': empty label before '='");
  }
  size_t star = rest.find('*');
  if (star != std::string::npos) {
    try {
      size_t used = 0;
      m.testScale = std::stod(rest.substr(star + 1), &used);
      if (used != rest.size() - star - 1) throw std::invalid_argument("trailing characters");
    } catch (const std::exception&) {
      throw std::invalid_argument("method spec '" + spec + "': bad scale after '*'");
    }
    if (!(m.testScale > 0)) throw std::invalid_argument("method spec '" + spec + "': scale must be positive");
    rest = rest.substr(0, star);
  }
  if (m.label.empty()) m.label = rest;
  // method[+modifier]...: separate-direct, direct-in-chains, mis-balance, mis-power, or a method parameter name:value.
  std::vector<std::string> parts;
  for (size_t from = 0;;) {
    const size_t plus = rest.find('+', from);
    parts.push_back(rest.substr(from, plus == std::string::npos ? std::string::npos : plus - from));
    if (plus == std::string::npos) break;
    from = plus + 1;
  }
  m.method = findMethod(parts.front()).name();
  for (size_t i = 1; i < parts.size(); ++i) {
    const std::string& mod = parts[i];
    if (mod == "separate-direct" || mod == "direct-in-chains") {
      const ChainJobSpec* chain = findChainJobSpec(m.method);
      if (!chain || !chain->allowsSeparateDirect())
        throw std::invalid_argument("method spec '" + spec + "': " + m.method + " cannot render the direct light apart");
      m.directLight = mod == "separate-direct" ? DirectLight::Separate : DirectLight::Chains;
      continue;
    }
    if (mod == "mis-balance" || mod == "mis-power") {
      m.heuristic = mod == "mis-balance" ? MisHeuristic::Balance : MisHeuristic::Power;
      continue;
    }
    const size_t colon = mod.find(':');
    if (colon == std::string::npos || colon == 0)
      throw std::invalid_argument("method spec '" + spec + "': '+" + mod +
                                  "' is neither separate-direct, direct-in-chains, mis-balance, mis-power nor a parameter name:value");
    m.params[mod.substr(0, colon)] = mod.substr(colon + 1);
  }
  try {
    findMethod(m.method).checkParams(m.params);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("method spec '" + spec + "': " + e.what());
  }
  return m;
}

uint64_t runSeed(uint64_t baseSeed, const std::string& scene, const std::string& method, int budgetIndex, int run) {
  return hashKeys(baseSeed, fnv1a64(scene), fnv1a64(method), uint64_t(budgetIndex), uint64_t(run));
}

namespace {

void logLine(const EvalConfig& cfg, const std::string& line) {
  if (cfg.verbose) std::fprintf(stderr, "[eval] %s\n", line.c_str());
}

// Work units of a run: spp (sample methods) or mutations per pixel (Markov chains).
void setWork(RenderSettings& s, double work) {
  if (isMarkovChainMethod(s.method))
    s.mutationsPerPixel = work;
  else
    s.spp = std::max(1, int(std::lround(work)));
}
double minWork(const std::string& m) { return isMarkovChainMethod(m) ? 0.05 : 1.0; }

// time(work) = fixed + perWork * work. `fixed` comes from the smallest calibration job; perWork is the
// least-squares slope through (work, time - fixed) over the larger calibration job and every run since,
// so it keeps improving as runs come in.
struct TimeModel {
  double fixed = 0, perWork = 0;
  double sumWT = 0, sumWW = 0;
  double workFor(double budget, const std::string& m) const {
    double w = perWork > 0 ? (budget - fixed) / perWork : minWork(m);
    w = std::max(w, minWork(m));
    return isMarkovChainMethod(m) ? w : std::round(w);
  }
  void observe(double work, double seconds) {
    if (work <= 0) return;
    sumWT += work * std::max(seconds - fixed, 0.0);
    sumWW += work * work;
    if (sumWT > 0) perWork = sumWT / sumWW;
  }
};

struct RunOutput {
  std::vector<Color> image;
  double seconds = 0;
  double planSeconds = -1;  // -1: not measured (farm runs)
  uint64_t samples = 0;
  ChainStats stats;
  int chains = 0, stuckChains = 0;
};

uint64_t sum(const std::vector<uint64_t>& v) {
  uint64_t s = 0;
  for (uint64_t x : v) s += x;
  return s;
}

std::pair<uint64_t, uint64_t> proposedAccepted(const ChainStats& st) {
  uint64_t p = sum(st.proposedPerLength), a = sum(st.acceptedPerLength);
  if (p == 0) {
    p = sum(st.proposedPerKind);
    a = sum(st.acceptedPerKind);
  }
  return {p, a};
}

RunOutput renderOnce(const EvalConfig& cfg, const EvalScene& es, const RenderScene& scene,
                     const RenderSettings& settings) {
  RunOutput out;
  if (cfg.farm) {
    FarmRunResult r = cfg.farm(es, settings);
    out.image = std::move(r.image);
    out.seconds = r.seconds;
    out.samples = r.samples;
    out.stats = r.stats;
    out.chains = isMarkovChainMethod(settings.method) ? r.units : 0;
    return out;
  }
  JobRun run = runJobInProcess(scene, settings, cfg.threads);
  out.image = std::move(run.image);
  out.seconds = run.seconds;
  out.planSeconds = run.planSeconds;
  out.samples = run.merged.samples;
  out.stats = run.merged.stats;
  if (isMarkovChainMethod(settings.method)) {
    out.chains = int(run.unitStats.size());
    for (const ChainStats& st : run.unitStats) {
      auto [p, a] = proposedAccepted(st);
      if (double(p) >= cfg.stability.stuckMinProposals && double(a) < cfg.stability.stuckAcceptance * double(p))
        ++out.stuckChains;
    }
  }
  return out;
}

std::string safeName(const std::string& s) {
  std::string o;
  for (char c : s) o += (std::isalnum((unsigned char)c) || c == '-' || c == '_' || c == '.') ? c : '_';
  return o;
}

// Calibration (equal time), the R runs at every budget, and the error map of one method on one scene.
void evalMethod(const EvalConfig& cfg, const EvalScene& es, const RenderScene& sceneRef, const RenderSettings& base,
                const Reference& ref, const MethodSpec& ms, EvalResult& result) {
  const RenderScene* scene = &sceneRef;
  const int largest = int(cfg.budgets.size()) - 1;
  RenderSettings settings = base;
  settings.method = ms.method;
  settings.directLight = ms.directLight;
  if (ms.heuristic) settings.integrator.heuristic = *ms.heuristic;
  for (const auto& [name, value] : ms.params) settings.params[name] = value;
  if (separatesDirect(settings)) settings.spp = 0;  // the direct pass sized by the plan from the work (mutations per pixel)
  settings.chains = cfg.base.chains;
  settings.samplesPerUnit = cfg.base.samplesPerUnit;

  // ---- Calibration (equal time) -------------------------------------------------------------
  // The smallest job measures the fixed cost (bootstrap, planning). Then the work grows until the extra
  // time is large enough to measure the cost per unit of work above timing noise: a quarter of the
  // smallest budget (at least 0.1 s); each step multiplies the work by 2..16, aiming at that target.
  TimeModel model;
  if (!cfg.equalSamples) {
    const double target = std::max(0.1, 0.25 * *std::min_element(cfg.budgets.begin(), cfg.budgets.end()));
    RenderSettings cal = settings;
    cal.seed = hashKeys(cfg.seed, fnv1a64(es.name), fnv1a64(ms.label), uint64_t(0xca1b));
    const double w1 = minWork(ms.method);
    setWork(cal, w1);
    const double t1 = renderOnce(cfg, es, *scene, cal).seconds;
    double w2 = w1, t2 = t1;
    for (int step = 0; step < 16 && t2 - t1 < target; ++step) {
      double grow = t2 - t1 > 0.01 ? std::clamp(1.5 * target / (t2 - t1), 2.0, 16.0) : 8.0;
      w2 = isMarkovChainMethod(ms.method) ? w2 * grow : std::ceil(w2 * grow);
      setWork(cal, w2);
      t2 = renderOnce(cfg, es, *scene, cal).seconds;
    }
    model.perWork = t2 > t1 ? (t2 - t1) / (w2 - w1) : t2 / w2;
    model.fixed = std::max(0.0, t1 - model.perWork * w1);
    model.observe(w2, t2);
    result.calibrations.push_back({es.name, ms.label, model.fixed, model.perWork});
    logLine(cfg, fmt::format("{} {}: calibration {:.3g} s fixed + {:.3g} s per {}", es.name, ms.label, model.fixed,
                             model.perWork, isMarkovChainMethod(ms.method) ? "mutation per pixel" : "spp"));
  }

  std::vector<std::pair<double, std::vector<Color>>> largestImages;  // (relMSE, image) at the largest budget
  const std::vector<int> bands = brightnessBands(ref.image);
  for (int bi = 0; bi < int(cfg.budgets.size()); ++bi) {
    const double budget = cfg.budgets[bi];
    for (int run = 0; run < cfg.runs; ++run) {
      RenderSettings rs = settings;
      rs.seed = runSeed(cfg.seed, es.name, ms.label, bi, run);
      const double work = cfg.equalSamples ? budget : model.workFor(budget, ms.method);
      setWork(rs, work);
      RunOutput out = renderOnce(cfg, es, *scene, rs);
      if (!cfg.equalSamples) model.observe(work, out.seconds);
      if (out.image.size() != ref.image.size())
        throw std::runtime_error(fmt::format("eval: {} {} rendered {} pixels, the reference has {}", es.name,
                                             ms.label, out.image.size(), ref.image.size()));
      // Test hooks: a deliberately biased method, an injected outlier run.
      if (ms.testScale != 1.0)
        for (Color& c : out.image) c *= float(ms.testScale);
      const OutlierInjection* inj = cfg.injectOutlier ? &*cfg.injectOutlier : nullptr;
      if (inj && inj->method == ms.label && inj->run == run && (inj->budgetIndex < 0 || inj->budgetIndex == bi))
        for (size_t i = 0; i < out.image.size(); ++i)
          out.image[i] = ref.image[i] + float(inj->factor) * (out.image[i] - ref.image[i]);

      RunRecord rec;
      rec.scene = es.name;
      rec.method = ms.label;
      rec.mode = cfg.farm ? "farm" : "local";
      rec.budgetIndex = bi;
      rec.budget = budget;
      rec.run = run;
      rec.seed = rs.seed;
      rec.seconds = out.seconds;
      rec.planSeconds = out.planSeconds;
      rec.work = isMarkovChainMethod(ms.method) ? rs.mutationsPerPixel : double(rs.spp);
      rec.samples = out.samples;
      rec.metrics = computeMetrics(out.image, ref.image, cfg.eps);
      rec.bandRelMSE = bandRelMse(out.image, ref.image, bands, cfg.eps);
      rec.width = ref.info.width;
      rec.markovChain = isMarkovChainMethod(ms.method);
      if (rec.markovChain) {
        rec.proposedPerLength = out.stats.proposedPerLength;
        rec.acceptedPerLength = out.stats.acceptedPerLength;
        rec.kinds = findMethod(ms.method).mutationKinds();
        rec.proposedPerKind = out.stats.proposedPerKind;
        rec.acceptedPerKind = out.stats.acceptedPerKind;
        auto [p, a] = proposedAccepted(out.stats);
        rec.acceptance = p > 0 ? double(a) / double(p) : -1;  // -1: not reported (farm runs)
        rec.chains = out.chains;
        rec.stuckChains = out.stuckChains;
        rec.idealRelMSE = idealLuminanceChainRelMse(ref.image, double(out.samples), cfg.eps);
        rec.bandIdeal = idealLuminanceChainBands(ref.image, bands, double(out.samples), cfg.eps);
      }
      logLine(cfg, fmt::format("{} {} budget {} run {}: {:.2f} s, work {:.3g}, relMSE {:.4g}, mean {:+.2f}%{}{}",
                               es.name, ms.label, budget, run, rec.seconds, rec.work, rec.metrics.relMSE,
                               100 * rec.metrics.meanErr,
                               rec.markovChain ? fmt::format(", acceptance {:.3f}", rec.acceptance) : "",
                               rec.idealRelMSE > 0 ? fmt::format(", {:.1f}x an ideal chain's", rec.metrics.relMSE / rec.idealRelMSE) : ""));
      if (bi == largest && cfg.errorMaps) largestImages.emplace_back(rec.metrics.relMSE, std::move(out.image));
      result.runs.push_back(std::move(rec));
    }
  }
  // Error map and image of the median run at the largest budget.
  if (cfg.errorMaps && !largestImages.empty()) {
    std::sort(largestImages.begin(), largestImages.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    const auto& median = largestImages[(largestImages.size() - 1) / 2].second;
    const std::string stem = safeName(es.name) + "_" + safeName(ms.label);
    writeErrorMapPng((fs::path(cfg.outDir) / "maps" / (stem + "_error.png")).string(), base.width, base.height,
                     relativeErrorMap(median, ref.image, cfg.eps));
    writePng((fs::path(cfg.outDir) / "maps" / (stem + "_image.png")).string(), base.width, base.height, median);
  }
}

}  // namespace

void writeEvalOutputs(const EvalConfig& cfg, EvalResult& result) {
  std::map<std::string, ReferenceNoise> noise;
  for (const ReferenceInfo& r : result.refs) noise[r.scene] = r.noise;
  result.stability = analyzeStability(result.runs, noise, cfg.stability);
  fs::create_directories(cfg.outDir);
  auto open = [&](const std::string& name) {
    std::ofstream os(fs::path(cfg.outDir) / name);
    if (!os) throw std::runtime_error((fs::path(cfg.outDir) / name).string() + ": cannot write");
    return os;
  };
  {
    auto os = open("runs.csv");
    writeRunsCsv(os, result.runs);
  }
  {
    auto os = open("acceptance.csv");
    writeAcceptanceCsv(os, result.runs);
  }
  {
    auto os = open("kinds.csv");
    writeKindsCsv(os, result.runs);
  }
  {
    auto os = open("bands.csv");
    writeBandsCsv(os, result.runs);
  }
  {
    auto os = open("refs.csv");
    writeRefsCsv(os, result.refs);
  }
  if (!result.calibrations.empty()) {
    auto os = open("calibration.csv");
    os << "scene,method,fixed_seconds,seconds_per_work\n";
    for (const Calibration& c : result.calibrations)
      os << fmt::format("{},{},{:.6g},{:.6g}\n", c.scene, c.method, c.fixedSeconds, c.perWork);
  }
  {
    auto os = open("summary.md");
    writeSummary(os, cfg, result);
  }
}

EvalResult runEval(const EvalConfig& cfg) {
  if (cfg.scenes.empty()) throw std::invalid_argument("eval: no scenes");
  if (cfg.methods.empty()) throw std::invalid_argument("eval: no methods");
  if (cfg.budgets.empty()) throw std::invalid_argument("eval: no budgets");
  for (double b : cfg.budgets)
    if (!(b > 0)) throw std::invalid_argument(fmt::format("eval: budget {} is not positive", b));
  if (cfg.runs < 1) throw std::invalid_argument("eval: --runs must be >= 1");
  if (cfg.outDir.empty()) throw std::invalid_argument("eval: --out is required");
  if (!cfg.userReference.empty() && cfg.scenes.size() != 1)
    throw std::invalid_argument("eval: --reference needs exactly one scene");
  for (size_t i = 0; i < cfg.methods.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (cfg.methods[i].label == cfg.methods[j].label)
        throw std::invalid_argument("eval: method label '" + cfg.methods[i].label + "' given twice");
  fs::create_directories(fs::path(cfg.outDir) / "maps");

  EvalResult result;
  for (const EvalScene& es : cfg.scenes) {
    SceneDesc desc = es.desc;
    RenderSettings base = cfg.base;
    if (base.width > 0) desc.camera.width = base.width;
    if (base.height > 0) desc.camera.height = base.height;
    base.width = desc.camera.width;
    base.height = desc.camera.height;
    if (cfg.depthFromScene) {
      if (desc.maxDepth) base.integrator.maxDepth = *desc.maxDepth;
      if (desc.rrDepth) base.integrator.rrDepth = *desc.rrDepth;
    }
    std::unique_ptr<RenderScene> scene = RenderScene::build(desc);

    // ---- Reference ------------------------------------------------------------------------------
    Reference ref;
    if (!cfg.userReference.empty()) {
      ref = loadUserReference(cfg.userReference, es.name, base.width, base.height);
    } else {
      std::string hash;
      if (cfg.cacheReferences && !desc.sourceFile.empty()) hash = sceneContentHash(desc);
      logLine(cfg, fmt::format("{}: reference ({} spp={} in {} parts)", es.name, cfg.reference.method,
                               cfg.reference.spp, cfg.reference.parts));
      ref = obtainReference(*scene, base, cfg.reference, es.name, hash, (fs::path(cfg.outDir) / "refs").string(),
                            cfg.eps, cfg.threads);
    }
    ref.info.width = base.width;
    ref.info.height = base.height;
    logLine(cfg, fmt::format("{}: reference {}{}: relMSE floor {:.3g}, mean rel. std. error {:.3g}", es.name,
                             ref.info.source, ref.info.cached ? " (cached)" : "", ref.info.noise.relMSEFloor,
                             ref.info.noise.meanRelStdErr));
    result.refs.push_back(ref.info);
    if (cfg.errorMaps) writePng((fs::path(cfg.outDir) / "maps" / (safeName(es.name) + "_reference.png")).string(),
                                base.width, base.height, ref.image);

    for (const MethodSpec& ms : cfg.methods) {
      const size_t runsBefore = result.runs.size(), calibrationsBefore = result.calibrations.size();
      try {
        evalMethod(cfg, es, *scene, base, ref, ms, result);
      } catch (const std::exception& e) {
        // The method cannot render this scene: keep the other methods' results and report why.
        result.runs.resize(runsBefore);
        result.calibrations.resize(calibrationsBefore);
        result.failures.push_back({es.name, ms.label, e.what()});
        logLine(cfg, fmt::format("{} {}: FAILED: {}", es.name, ms.label, e.what()));
      }
    }
    writeEvalOutputs(cfg, result);  // keep what was measured so far
  }

  if (cfg.charts) {
    const std::string script =
        cfg.chartScript.empty() ? std::string(MLTFARM_SOURCE_DIR) + "/tools/eval/charts.py" : cfg.chartScript;
    const std::string cmd = fmt::format("'{}' '{}' '{}'", cfg.python, script, cfg.outDir);
    logLine(cfg, "charts: " + cmd);
    if (std::system(cmd.c_str()) != 0)
      std::fprintf(stderr, "[eval] warning: the chart script failed (is python3-matplotlib installed?): %s\n",
                   cmd.c_str());
  }
  writeEvalOutputs(cfg, result);  // the summary links the charts that now exist
  return result;
}

}  // namespace mlt::eval
