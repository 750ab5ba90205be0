// `mltfarm eval`: accuracy against speed. Scenes x methods x budgets x R runs, each run a complete job with
// its own seed, compared with a reference; writes runs.csv, acceptance.csv, refs.csv, charts, error maps
// and summary.md under --out (see tools/eval/harness.h). Example:
//   mltfarm eval --scenes scenes/cornell-box.xml --methods pt,bdpt,pssmlt,mmlt --runs 4 --budgets 1,2,4 --out ev
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/io/exr_io.h"
#include "common/methods/chain_report.h"
#include "common/scene/scene_loader.h"
#include "common/settings/direct_light_name.h"
#include "tools/cli/commands.h"
#include "tools/eval/harness.h"

namespace mlt::cli {
namespace {

struct EvalCliOptions {
  std::vector<std::string> scenes, methods{"pt", "lt", "bdpt", "pssmlt", "pssmlt-bdpt", "mmlt"}, defines;
  std::vector<double> budgets{1, 2, 4, 8};
  std::string out, reference, refMethod = "bdpt", injectOutlier, python = "/usr/bin/python3";
  int runs = 3, threads = 0, width = 0, height = 0, maxDepth = 0, rrDepth = 0, refSpp = 1024, refParts = 4;
  int chains = 0, bootstrap = 0;
  float largeStep = -1.0f;  // the method's default
  std::string kernel = "kelemen";
  float s1 = 1.0f / 1024, s2 = 1.0f / 64, sigma = 0.01f;  // RenderSettings' defaults (see settings_options.h)
  double eps = 1e-2, outlierRatio = 4, biasAlpha = 1e-3, minBias = 0.01;
  uint64_t seed = 1;
  bool equalSamples = false, farm = false, noCharts = false, noMaps = false, noCache = false, quiet = false;
};

std::vector<std::string> splitCommas(const std::vector<std::string>& items) {
  std::vector<std::string> out;
  for (const std::string& item : items) {
    std::stringstream ss(item);
    for (std::string s; std::getline(ss, s, ',');)
      if (!s.empty()) out.push_back(s);
  }
  return out;
}

std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// --farm: every run is `mltfarm render SCENE --farm ...` in a child process (the command users run: it
// starts a coordinator and local worker processes, submits, merges, develops), timed from the outside;
// the image, the work done and the chains' acceptance statistics are read back from the EXR it writes
// (the chain report keys of common/methods/chain_report.h; counts are rebuilt from the recorded rates).
eval::FarmRunner makeFarmRunner(const std::map<std::string, std::string>& defines, int threads,
                                const std::string& workDir) {
  std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  return [=](const eval::EvalScene& scene, const RenderSettings& s) {
    std::filesystem::create_directories(workDir);
    const std::string exr = workDir + "/farm-run.exr", log = workDir + "/farm-run.log";
    std::string cmd = fmt::format(
        "{} render {} -o {} --farm -q -m {} --seed {} --width {} --height {} --max-depth {} --rr-depth {}",
        shellQuote(self), shellQuote(std::filesystem::absolute(scene.desc.sourceFile).string()), shellQuote(exr), s.method, s.seed, s.width,
        s.height, s.integrator.maxDepth, s.integrator.rrDepth);
    if (isMarkovChainMethod(s.method))
      cmd += fmt::format(
          " --mutations-per-pixel {:.17g} --bootstrap {}{} --chains {} --kernel {} --s1 {} "
          "--s2 {} --sigma {}",
          s.mutationsPerPixel, s.bootstrapSamples,
          s.largeStepProb >= 0 ? fmt::format(" --large-step {}", s.largeStepProb) : std::string(), s.chains,
          s.kernel == MutationKernel::Gaussian ? "gaussian" : "kelemen", s.kelemenS1, s.kelemenS2, s.gaussianSigma);
    if (isMarkovChainMethod(s.method)) {  // spp 0, or an automatic choice: the direct pass sized by the plan
      cmd += fmt::format(" --direct-light {}", directLightName(s.directLight));
      if (separatesDirect(s) && s.spp > 0) cmd += fmt::format(" --spp {}", s.spp);
    } else
      cmd += fmt::format(" --spp {}", s.spp);
    if (threads > 0) cmd += fmt::format(" --threads {}", threads);
    for (const auto& [k, v] : defines) cmd += " -D " + shellQuote(k + "=" + v);
    cmd += " > " + shellQuote(log) + " 2>&1";
    const auto start = std::chrono::steady_clock::now();
    const int rc = std::system(cmd.c_str());
    eval::FarmRunResult r;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (rc != 0) {
      std::ifstream in(log);
      std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      if (text.size() > 2000) text = text.substr(text.size() - 2000);
      throw std::runtime_error("--farm: `" + cmd + "` failed:\n" + text);
    }
    ExrImage img = readExr(exr);
    r.image = std::move(img.rgb);
    auto num = [&](const char* key) {
      auto it = img.metadata.numbers.find(key);
      return it == img.metadata.numbers.end() ? 0.0 : it->second;
    };
    r.samples = uint64_t(isMarkovChainMethod(s.method) ? num("mutations") : num("samples"));
    r.units = int(isMarkovChainMethod(s.method) ? num("chains") : num("workUnits"));
    if (isMarkovChainMethod(s.method)) {
      const ChainReport report = chainReportFromMetadata(img.metadata);
      if (report.hasAcceptance) {
        auto accepted = [](double rate, uint64_t proposed) { return uint64_t(std::llround(rate * double(proposed))); };
        ChainStats& st = r.stats;
        uint64_t proposed = 0;
        for (const MutationKindReport& k : report.kinds) {
          st.proposedPerKind.push_back(k.proposed);
          st.acceptedPerKind.push_back(accepted(k.acceptance, k.proposed));
          proposed += k.proposed;
        }
        if (report.lengths.empty()) {  // one target over all lengths: index 0 (as ChainStats does)
          st.proposedPerLength = {proposed};
          st.acceptedPerLength = {accepted(report.acceptance, proposed)};
        } else {
          for (const ChainLengthReport& l : report.lengths) {
            if (int(st.proposedPerLength.size()) <= l.k) {
              st.proposedPerLength.resize(l.k + 1, 0);
              st.acceptedPerLength.resize(l.k + 1, 0);
            }
            st.proposedPerLength[l.k] = l.mutations;
            st.acceptedPerLength[l.k] = accepted(l.acceptance, l.mutations);
          }
        }
      }
    }
    return r;
  };
}

eval::OutlierInjection parseInjection(const std::string& s) {
  // METHOD:RUN[:FACTOR]
  eval::OutlierInjection inj;
  std::stringstream ss(s);
  std::string method, run, factor;
  std::getline(ss, method, ':');
  std::getline(ss, run, ':');
  std::getline(ss, factor, ':');
  try {
    if (method.empty() || run.empty()) throw std::invalid_argument("");
    inj.method = method;
    inj.run = std::stoi(run);
    if (!factor.empty()) inj.factor = std::stod(factor);
  } catch (const std::exception&) {
    throw std::invalid_argument("--inject-outlier '" + s + "': expected METHOD:RUN[:FACTOR]");
  }
  return inj;
}

CommandRun setupEval(CLI::App& sub) {
  auto o = std::make_shared<EvalCliOptions>();
  sub.add_option("--scenes", o->scenes, "Scene files, comma-separated")->required()->delimiter(',');
  sub.add_option("--methods", o->methods,
                 "Methods, comma-separated (" + methodNameList() + "). A spec LABEL=METHOD*SCALE "
                 "multiplies every image of the method by SCALE (test hook: a deliberately biased method)")
      ->delimiter(',')
      ->capture_default_str();
  sub.add_option("--runs", o->runs, "Independent runs (different job seeds) per scene x method x budget")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub.add_option("--budgets", o->budgets,
                 "Budgets, comma-separated: seconds per run (equal time), or with --equal-samples spp "
                 "(pt/lt/bdpt) and mutations per pixel (Markov chains)")
      ->delimiter(',')
      ->capture_default_str();
  sub.add_flag("--equal-samples", o->equalSamples, "Budgets are samples (spp / mutations per pixel), not seconds");
  sub.add_option("-o,--out", o->out, "Output directory")->required();
  sub.add_option("--reference", o->reference, "Reference EXR (one scene only); default: render and cache one");
  sub.add_option("--ref-method", o->refMethod, "Method of the rendered reference")->capture_default_str();
  sub.add_option("--ref-spp", o->refSpp, "Samples per pixel of the rendered reference (over all parts)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub.add_option("--ref-parts", o->refParts, "Independent parts of the reference (its noise estimate)")
      ->capture_default_str()
      ->check(CLI::Range(2, 1024));
  sub.add_flag("--no-ref-cache", o->noCache, "Always render the reference (do not read or write OUT/refs)");
  sub.add_flag("--farm", o->farm, "Run every job through the farm (coordinator + worker processes)");
  sub.add_option("--width", o->width, "Film width (default: the scene's)")->check(CLI::PositiveNumber);
  sub.add_option("--height", o->height, "Film height (default: the scene's)")->check(CLI::PositiveNumber);
  auto* maxDepth = sub.add_option("--max-depth", o->maxDepth, "Maximum path segments (default: the scene's, else 5)")
                       ->check(CLI::Range(-1, 1 << 20));
  auto* rrDepth = sub.add_option("--rr-depth", o->rrDepth, "Russian roulette depth (default: the scene's, else 5)")
                      ->check(CLI::NonNegativeNumber);
  sub.add_option("--chains", o->chains, "Markov chains per job (0 = automatic)")->check(CLI::NonNegativeNumber);
  sub.add_option("--bootstrap", o->bootstrap, "Markov chain methods: bootstrap candidates per path length; 0 = automatic (about 3% of the job's time: of the mutations, or of the time budget; b is refined by the chains' large steps, except veach-mlt's)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sub.add_option("--large-step", o->largeStep, "Large-step probability (default: each method's, 0.3; rjmlt 0.1)")
      ->check(CLI::Range(0.0, 1.0));
  sub.add_option("--kernel", o->kernel,
                 "Markov chain methods: small-step kernel, kelemen (exponential, --s1/--s2) or gaussian (--sigma)")
      ->capture_default_str()
      ->check(CLI::IsMember({"kelemen", "gaussian"}));
  // Same validation as `mltfarm render` (settings_options.cpp): steps in (0, 1], s1 <= s2 checked below.
  const CLI::Validator unitStep(
      [](std::string& value) -> std::string {
        double x = 0;
        if (!CLI::detail::lexical_cast(value, x)) return "'" + value + "' is not a number";
        return x > 0 && x <= 1 ? std::string() : "must be in (0, 1], got " + value;
      },
      "(0,1]", "UNIT_STEP");
  sub.add_option("--s1", o->s1, "Kelemen kernel: smallest step")->check(unitStep);
  sub.add_option("--s2", o->s2, "Kelemen kernel: largest step (at least --s1)")->check(unitStep);
  sub.add_option("--sigma", o->sigma, "Gaussian kernel: standard deviation")->check(unitStep);
  sub.add_option("--eps", o->eps, "relMSE epsilon: (x-r)^2 / (r^2 + eps)")->capture_default_str()->check(CLI::PositiveNumber);
  sub.add_option("--seed", o->seed, "Base seed (run seeds derive from it)")->capture_default_str();
  sub.add_option("-t,--threads", o->threads, "Threads per run (default: every core)")->check(CLI::NonNegativeNumber);
  sub.add_option("--outlier-ratio", o->outlierRatio, "A run is an outlier above this x its group's median relMSE")
      ->capture_default_str();
  sub.add_option("--bias-alpha", o->biasAlpha, "Family-wise significance level of the bias test")->capture_default_str();
  sub.add_option("--min-bias", o->minBias, "Smallest relative brightness error called bias")->capture_default_str();
  sub.add_option("--inject-outlier", o->injectOutlier,
                 "Test hook METHOD:RUN[:FACTOR]: amplify that run's error by FACTOR (default 10) at every budget");
  sub.add_option("-D,--define", o->defines, "Scene parameter name=value (Mitsuba's -D), repeatable");
  sub.add_option("--python", o->python, "Python with matplotlib for the charts")->capture_default_str();
  sub.add_flag("--no-charts", o->noCharts, "Do not run the chart script");
  sub.add_flag("--no-maps", o->noMaps, "Do not write error maps and images");
  sub.add_flag("-q,--quiet", o->quiet, "No progress lines");

  return [o, maxDepth, rrDepth]() -> int {
    if (o->s2 < o->s1)  // the kernel's steps lie in [s1, s2] (Kelemen et al. 2002, eq. 9)
      throw std::invalid_argument(fmt::format("--s2 ({}) must be at least --s1 ({})", o->s2, o->s1));
    eval::EvalConfig cfg;
    std::map<std::string, std::string> defines;
    for (const std::string& d : o->defines) {
      size_t eq = d.find('=');
      if (eq == std::string::npos || eq == 0) throw std::invalid_argument("--define '" + d + "': expected name=value");
      defines[d.substr(0, eq)] = d.substr(eq + 1);
    }
    for (const std::string& path : splitCommas(o->scenes)) {
      eval::EvalScene es;
      es.name = std::filesystem::path(path).stem().string();
      for (const auto& other : cfg.scenes)
        if (other.name == es.name) throw std::invalid_argument("--scenes: two scenes named '" + es.name + "'");
      es.desc = loadScene(path, defines);
      cfg.scenes.push_back(std::move(es));
    }
    for (const std::string& m : splitCommas(o->methods)) cfg.methods.push_back(eval::parseMethodSpec(m));
    cfg.budgets = o->budgets;
    cfg.runs = o->runs;
    cfg.equalSamples = o->equalSamples;
    cfg.outDir = o->out;
    cfg.userReference = o->reference;
    cfg.reference.method = findMethod(o->refMethod).name();
    cfg.reference.spp = o->refSpp;
    cfg.reference.parts = o->refParts;
    cfg.cacheReferences = !o->noCache;
    cfg.base.width = o->width;
    cfg.base.height = o->height;
    if ((o->width > 0) != (o->height > 0)) throw std::invalid_argument("--width and --height go together");
    cfg.depthFromScene = !(maxDepth->count() || rrDepth->count());
    if (maxDepth->count()) cfg.base.integrator.maxDepth = o->maxDepth;
    if (rrDepth->count()) cfg.base.integrator.rrDepth = o->rrDepth;
    cfg.base.chains = o->chains;
    cfg.base.bootstrapSamples = o->bootstrap;
    cfg.base.largeStepProb = o->largeStep;
    cfg.base.kernel = o->kernel == "gaussian" ? MutationKernel::Gaussian : MutationKernel::Kelemen;
    cfg.base.kelemenS1 = o->s1;
    cfg.base.kelemenS2 = o->s2;
    cfg.base.gaussianSigma = o->sigma;
    cfg.eps = o->eps;
    cfg.seed = o->seed;
    cfg.threads = o->threads;
    cfg.stability.outlierRatio = o->outlierRatio;
    cfg.stability.biasAlpha = o->biasAlpha;
    cfg.stability.minBias = o->minBias;
    if (!o->injectOutlier.empty()) cfg.injectOutlier = parseInjection(o->injectOutlier);
    cfg.python = o->python;
    cfg.charts = !o->noCharts;
    cfg.errorMaps = !o->noMaps;
    cfg.verbose = !o->quiet;
    {
      auto join = [](const std::vector<std::string>& v) {
        std::string s;
        for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
        return s;
      };
      std::string budgets;
      for (double b : o->budgets) budgets += (budgets.empty() ? "" : ",") + fmt::format("{:g}", b);
      // The Markov chain parameters always (their defaults may change); the others when given.
      std::string chain = o->largeStep >= 0 ? fmt::format(" --large-step {}", o->largeStep) : std::string();
      chain += fmt::format(" --kernel {}", o->kernel);
      if (o->kernel == "gaussian")
        chain += fmt::format(" --sigma {}", o->sigma);
      else
        chain += fmt::format(" --s1 {} --s2 {}", o->s1, o->s2);
      if (o->chains > 0) chain += fmt::format(" --chains {}", o->chains);
      if (o->bootstrap > 0) chain += fmt::format(" --bootstrap {}", o->bootstrap);
      cfg.commandLine = fmt::format("mltfarm eval --scenes {} --methods {} --runs {} --budgets {}{}{}{} --out {}",
                                    join(splitCommas(o->scenes)), join(splitCommas(o->methods)), o->runs, budgets,
                                    o->equalSamples ? " --equal-samples" : "",
                                    o->width > 0 ? fmt::format(" --width {} --height {}", o->width, o->height) : "",
                                    chain, o->out);
    }
    if (o->farm) cfg.farm = makeFarmRunner(defines, o->threads, o->out + "/farm-tmp");
    if (o->quiet) spdlog::set_level(spdlog::level::warn);

    eval::EvalResult result = eval::runEval(cfg);
    int failing = 0;
    for (const auto& v : result.stability.verdicts) {
      if (v.ok()) continue;
      ++failing;
      std::fprintf(stderr, "%s / %s:", v.scene.c_str(), v.method.c_str());
      for (const auto& p : v.problems) std::fprintf(stderr, " %s.", p.c_str());
      std::fprintf(stderr, "\n");
    }
    for (const auto& f : result.failures) {
      ++failing;
      std::fprintf(stderr, "%s / %s: cannot render: %s\n", f.scene.c_str(), f.method.c_str(), f.error.c_str());
    }
    std::printf("eval: %zu runs, %d scene/method pairs with problems; see %s/summary.md\n", result.runs.size(),
                failing, cfg.outDir.c_str());
    return 0;
  };
}

const CommandRegistration kEval("eval", "Accuracy against speed: error vs time charts, stability, summary", setupEval);

}  // namespace
}  // namespace mlt::cli
