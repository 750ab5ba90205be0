#include "tools/eval/report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <thread>

#include <fmt/format.h>

#include "tools/eval/harness.h"
#include "tools/eval/stats.h"

namespace mlt::eval {

namespace fs = std::filesystem;

std::string machineDescription() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  int processors = 0;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0 && model == "unknown CPU") {
      auto colon = line.find(':');
      if (colon != std::string::npos) model = line.substr(line.find_first_not_of(" \t", colon + 1));
    }
    if (line.rfind("processor", 0) == 0) ++processors;
  }
  if (processors == 0) processors = int(std::thread::hardware_concurrency());
  return fmt::format("{} ({} cores)", model, processors);
}

namespace {

std::string safeName(const std::string& s) {
  std::string o;
  for (char c : s) o += (std::isalnum((unsigned char)c) || c == '-' || c == '_' || c == '.') ? c : '_';
  return o;
}

struct GroupStats {
  double relMSE = 0, relMSEStd = 0, seconds = 0, work = 0, meanErr = 0, meanErrStd = 0, acceptance = -1;
  double ideal = -1;  // mean of the runs' idealRelMSE (Markov chains), -1 when none has one
  int runs = 0, flagged = 0;
};

GroupStats groupStats(const std::vector<const RunRecord*>& g) {
  GroupStats s;
  std::vector<double> e, t, w, m, a, id;
  for (const RunRecord* r : g) {
    e.push_back(r->metrics.relMSE);
    t.push_back(r->seconds);
    w.push_back(r->work);
    m.push_back(r->metrics.meanErr);
    if (r->markovChain && r->acceptance >= 0) a.push_back(r->acceptance);
    if (r->idealRelMSE > 0) id.push_back(r->idealRelMSE);
    if (!r->flags.empty()) ++s.flagged;
  }
  s.runs = int(g.size());
  s.relMSE = mean(e);
  s.relMSEStd = stddev(e);
  s.seconds = mean(t);
  s.work = mean(w);
  s.meanErr = mean(m);
  s.meanErrStd = stddev(m);
  if (!a.empty()) s.acceptance = mean(a);
  if (id.size() == g.size()) s.ideal = mean(id);
  return s;
}

// Band means over a group's runs; ideal[b] is -1 unless every run has it.
struct BandStats {
  BandValues relMSE{}, ideal = kUnknownBands;
  double total = 0;
};

BandStats bandStats(const std::vector<const RunRecord*>& g) {
  BandStats s;
  if (g.empty()) return s;
  BandValues ideal{};
  bool allIdeal = true;
  for (const RunRecord* r : g)
    for (size_t b = 0; b < size_t(kBands); ++b) {
      s.relMSE[b] += r->bandRelMSE[b] / double(g.size());
      if (r->bandIdeal[b] >= 0) ideal[b] += r->bandIdeal[b] / double(g.size());
      else allIdeal = false;
    }
  if (allIdeal) s.ideal = ideal;
  for (double v : s.relMSE) s.total += v;
  return s;
}

std::string budgetText(const EvalConfig& cfg) {
  std::string s;
  for (double b : cfg.budgets) s += (s.empty() ? "" : ", ") + fmt::format("{:g}", b);
  return cfg.equalSamples ? "equal samples: " + s + " spp (pt/lt/bdpt) or mutations per pixel (chains)"
                          : "equal time: " + s + " s per run";
}

}  // namespace

void writeSummary(std::ostream& os, const EvalConfig& cfg, const EvalResult& result) {
  const std::string machine = machineDescription();
  const std::string budgets = budgetText(cfg);
  const std::string mode = cfg.farm ? "through the farm (coordinator + worker processes)" : "in-process";
  os << "# Accuracy against speed\n\n";
  os << fmt::format("- Machine: {}; threads per run: {}\n", machine,
                    cfg.threads > 0 ? std::to_string(cfg.threads) : std::string("all"));
  os << fmt::format("- Budgets ({}), {} runs per scene x method x budget, each with its own job seed; runs {}\n",
                    budgets, cfg.runs, mode);
  os << fmt::format("- Error: relMSE = mean (x - r)^2 / (r^2 + {:g}) over pixels and channels; meanErr = relative "
                    "error of the mean brightness\n",
                    cfg.eps);
  if (!cfg.commandLine.empty()) os << "- Command: `" << cfg.commandLine << "`\n";
  os << "\n";

  for (const ReferenceInfo& ref : result.refs) {
    const std::string scene = ref.scene, sn = safeName(scene);
    os << "## " << scene << "\n\n";
    os << fmt::format("Film {}x{}. Reference: {}{}. ", ref.width, ref.height, ref.source,
                      ref.cached ? " (cached)" : "");
    if (ref.noise.parts > 0)
      os << fmt::format("Its own noise: relMSE floor {:.3g} (a perfect image would measure this), mean brightness "
                        "+-{:.3g}% (1 std. error). Errors near the floor are not resolved.\n\n",
                        ref.noise.relMSEFloor, 100 * ref.noise.meanRelStdErr);
    else
      os << "Its noise level is unknown (user-supplied), so small errors may be the reference's own.\n\n";

    // Groups of this scene.
    std::vector<std::string> methods;
    std::map<std::pair<std::string, int>, std::vector<const RunRecord*>> groups;
    for (const RunRecord& r : result.runs) {
      if (r.scene != scene) continue;
      if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) methods.push_back(r.method);
      groups[{r.method, r.budgetIndex}].push_back(&r);
    }
    if (methods.empty()) {
      os << "No runs.\n\n";
      continue;
    }
    const std::string caption = fmt::format("*{}; {}; {} runs each.*", machine, budgets, cfg.runs);
    auto chart = [&](const std::string& file, const std::string& title) {
      if (fs::exists(fs::path(cfg.outDir) / file)) os << "![" << title << "](" << file << ")\n\n" << caption << "\n\n";
    };
    chart("error_time_" + sn + ".png", "relMSE against time, " + scene);

    // Ranking at equal time/samples, one column per budget.
    os << "### Ranking at equal " << (cfg.equalSamples ? "samples" : "time") << "\n\n";
    os << "Mean relMSE over runs (rank among methods) per budget; lower is better. "
       << "`~floor`: within 2x of the reference's own noise floor.\n\n| method |";
    for (double b : cfg.budgets) os << fmt::format(" {:g}{} |", b, cfg.equalSamples ? "" : " s");
    os << "\n|---|";
    for (size_t i = 0; i < cfg.budgets.size(); ++i) os << "---|";
    os << "\n";
    std::map<std::pair<std::string, int>, int> rank;
    for (int bi = 0; bi < int(cfg.budgets.size()); ++bi) {
      std::vector<std::pair<double, std::string>> order;
      for (const auto& m : methods)
        if (groups.count({m, bi})) order.emplace_back(groupStats(groups[{m, bi}]).relMSE, m);
      std::sort(order.begin(), order.end());
      for (size_t i = 0; i < order.size(); ++i) rank[{order[i].second, bi}] = int(i) + 1;
    }
    const int last = int(cfg.budgets.size()) - 1;
    std::vector<std::string> sorted = methods;
    std::sort(sorted.begin(), sorted.end(), [&](const std::string& a, const std::string& b) {
      return rank.count({a, last}) && rank.count({b, last}) ? rank[{a, last}] < rank[{b, last}] : a < b;
    });
    for (const auto& m : sorted) {
      os << "| " << m << " |";
      for (int bi = 0; bi <= last; ++bi) {
        auto it = groups.find({m, bi});
        if (it == groups.end()) {
          os << " - |";
          continue;
        }
        GroupStats s = groupStats(it->second);
        bool atFloor = ref.noise.parts > 0 && s.relMSE < 2 * ref.noise.relMSEFloor;
        os << fmt::format(" {:.3g} (#{}){} |", s.relMSE, rank[{m, bi}], atFloor ? " ~floor" : "");
      }
      os << "\n";
    }
    os << "\n";

    // Detail at the largest budget.
    os << fmt::format("At the largest budget ({:g}{}). *fixed cost*: the calibrated time every run pays whatever its "
                      "budget (bootstrap, planning); a budget below it leaves the method its minimum work.\n\n",
                      cfg.budgets[last], cfg.equalSamples ? "" : " s");
    os << "*over ideal*: the mean relMSE over that of an ideal chain (independent draws from the luminance target) "
          "with the same mutations (tools/eval/ideal_chain.h): what the chains' correlation costs where they render "
          "the whole image (a pass of the direct light can put a method below 1).\n\n";
    os << "| method | relMSE mean +- std | seconds | fixed cost s | work (spp or mutations/px) | "
          "mean brightness err | acceptance | over ideal | flagged runs |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& m : sorted) {
      auto it = groups.find({m, last});
      if (it == groups.end()) continue;
      GroupStats s = groupStats(it->second);
      std::string fixed = "-";
      for (const Calibration& c : result.calibrations)
        if (c.scene == scene && c.method == m) fixed = fmt::format("{:.2f}", c.fixedSeconds);
      os << fmt::format("| {} | {:.3g} +- {:.2g} | {:.2f} | {} | {:.3g} | {:+.2f}% +- {:.2f}% | {} | {} | {}/{} |\n", m,
                        s.relMSE, s.relMSEStd, s.seconds, fixed, s.work, 100 * s.meanErr, 100 * s.meanErrStd,
                        s.acceptance >= 0 ? fmt::format("{:.3f}", s.acceptance) : std::string("-"),
                        s.ideal > 0 ? fmt::format("{:.2g}x", s.relMSE / s.ideal) : std::string("-"), s.flagged,
                        s.runs);
    }
    os << "\n";

    // Where the error is, by the reference's brightness.
    os << "### Where the error is\n\n";
    os << "The mean relMSE at the largest budget split by the reference's brightness (tools/eval/bands.h: pixels "
          "ranked by reference luminance; the bands add up to the relMSE), with each band's share of it and, for "
          "Markov chains, the band over the same band of the ideal chain's (where the correlation costs most).\n\n";
    os << "| method |";
    for (int b = 0; b < kBands; ++b) os << " " << bandName(b) << " |";
    os << "\n|---|";
    for (int b = 0; b < kBands; ++b) os << "---|";
    os << "\n";
    for (const auto& m : sorted) {
      auto it = groups.find({m, last});
      if (it == groups.end()) continue;
      const BandStats bs = bandStats(it->second);
      os << "| " << m << " |";
      for (int b = 0; b < kBands; ++b) {
        const size_t i = size_t(b);
        os << fmt::format(" {:.2g} ({:.0f}%{}) |", bs.relMSE[i], bs.total > 0 ? 100 * bs.relMSE[i] / bs.total : 0.0,
                          bs.ideal[i] > 0 ? fmt::format(", {:.2g}x", bs.relMSE[i] / bs.ideal[i]) : std::string());
      }
      os << "\n";
    }
    os << "\n";

    // Stability.
    os << "### Stability\n\n";
    chart("spread_" + sn + ".png", "run-to-run spread, " + scene);
    chart("acceptance_" + sn + ".png", "acceptance per path length, " + scene);
    bool anyProblem = false;
    for (const MethodVerdict& v : result.stability.verdicts) {
      if (v.scene != scene) continue;
      if (v.ok()) continue;
      anyProblem = true;
      os << "- **" << v.method << "** fails:";
      for (const auto& p : v.problems) os << " " << p << ".";
      os << "\n";
    }
    std::string okList;
    for (const MethodVerdict& v : result.stability.verdicts)
      if (v.scene == scene && v.ok()) okList += (okList.empty() ? "" : ", ") + v.method;
    for (const MethodFailure& f : result.failures)
      if (f.scene == scene) {
        anyProblem = true;
        os << "- **" << f.method << "** cannot render this scene: " << f.error << "\n";
      }
    if (!okList.empty()) os << "- No failure detected for: " << okList << ".\n";
    if (!anyProblem && okList.empty()) os << "- No verdicts.\n";
    os << "\n";

    // Error maps.
    bool anyMap = false;
    for (const auto& m : methods) anyMap |= fs::exists(fs::path(cfg.outDir) / "maps" / (sn + "_" + safeName(m) + "_error.png"));
    if (anyMap) {
      os << "### Per-pixel error (median run at the largest budget)\n\n";
      os << "log10 relative squared error from -4 (black) to 1 (white); the rendered image below each map.\n\n| ";
      for (const auto& m : methods) os << m << " | ";
      os << "reference |\n|";
      for (size_t i = 0; i <= methods.size(); ++i) os << "---|";
      os << "\n| ";
      for (const auto& m : methods) os << "![](maps/" << sn << "_" << safeName(m) << "_error.png) | ";
      os << " |\n| ";
      for (const auto& m : methods) os << "![](maps/" << sn << "_" << safeName(m) << "_image.png) | ";
      os << "![](maps/" << sn << "_reference.png) |\n\n";
    }
  }
  os << "Tables: `runs.csv` (every run), `bands.csv` (every run's error by brightness band), `acceptance.csv` (per path length), `refs.csv` (references).\n";
}

}  // namespace mlt::eval
