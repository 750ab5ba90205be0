#include "tools/eval/stability.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <fmt/format.h>

#include "tools/eval/stats.h"

namespace mlt::eval {

namespace {

using GroupKey = std::tuple<std::string, std::string, int>;  // scene, method, budget index

bool hasFlag(const RunRecord& r, const std::string& kind) {
  for (const auto& f : r.flags)
    if (f.rfind(kind, 0) == 0) return true;
  return false;
}

void flagOutliers(std::vector<RunRecord*>& g, const StabilityConfig& cfg) {
  if (g.size() < 3) return;
  std::vector<double> err, logErr;
  for (RunRecord* r : g) {
    err.push_back(r->metrics.relMSE);
    logErr.push_back(std::log(std::max(r->metrics.relMSE, 1e-300)));
  }
  double med = median(err);
  double logMed = median(logErr), sigma = 1.4826 * mad(logErr);
  for (RunRecord* r : g) {
    double e = r->metrics.relMSE;
    if (!std::isfinite(e)) {
      r->flags.push_back("outlier:non-finite relMSE");
      continue;
    }
    double ratio = med > 0 ? e / med : (e > 0 ? INFINITY : 1);
    double z = sigma > 0 ? (std::log(std::max(e, 1e-300)) - logMed) / sigma : 0;
    bool byRatio = ratio > cfg.outlierRatio;
    bool byZ = g.size() >= 5 && z > cfg.robustZ && ratio > cfg.minRatio;
    if (byRatio || byZ) r->flags.push_back(fmt::format("outlier:relMSE {:.3g}x median (robust z {:.1f})", ratio, z));
  }
}

void flagBrightness(std::vector<RunRecord*>& g, const StabilityConfig& cfg) {
  const size_t n = g.size();
  if (n < 4) return;  // leave-one-out needs >= 3 others for a spread with >= 2 dof
  for (size_t i = 0; i < n; ++i) {
    std::vector<double> others;
    for (size_t j = 0; j < n; ++j)
      if (j != i && std::isfinite(g[j]->metrics.meanErr)) others.push_back(g[j]->metrics.meanErr);
    if (others.size() < 3) continue;
    double mi = g[i]->metrics.meanErr, mo = mean(others), so = stddev(others);
    double k = double(others.size());
    double d = mi - mo;
    if (!std::isfinite(mi) || std::fabs(d) < cfg.minBias) continue;
    double se = so * std::sqrt(1 + 1 / k);
    double p = se > 0 ? studentTwoSidedP(d / se, k - 1) : 0;
    if (p < cfg.runAlpha)
      g[i]->flags.push_back(fmt::format("brightness:mean {:+.2f}% vs {:+.2f}% of the other runs (p={:.1e})",
                                        100 * mi, 100 * mo, p));
  }
}

void flagStuck(RunRecord& r, const StabilityConfig& cfg) {
  if (!r.markovChain) return;
  std::string where;
  for (size_t k = 0; k < r.proposedPerLength.size(); ++k) {
    double prop = double(r.proposedPerLength[k]);
    double acc = k < r.acceptedPerLength.size() ? double(r.acceptedPerLength[k]) : 0;
    if (prop >= cfg.stuckMinProposals && acc / prop < cfg.stuckAcceptance)
      where += fmt::format("{}k={} acceptance {:.2g}", where.empty() ? "" : ", ", k, acc / prop);
  }
  if (r.stuckChains > 0)
    where += fmt::format("{}{} of {} chains below {:.2g} acceptance", where.empty() ? "" : ", ", r.stuckChains,
                         r.chains, cfg.stuckAcceptance);
  if (!where.empty()) r.flags.push_back("stuck:" + where);
}

// ", the worst at (x, y)", so that the pixels can be looked at in the run's image; nothing when the film's
// width is unknown (a record read back from runs.csv, whose flags column keeps the text of the first analysis).
std::string worstPixelText(const RunRecord& r) {
  if (r.width <= 0) return {};
  return fmt::format(", the worst at ({}, {})", r.metrics.worstPixel % uint64_t(r.width),
                     r.metrics.worstPixel / uint64_t(r.width));
}

void flagConcentrated(RunRecord& r, const StabilityConfig& cfg) {
  if (r.metrics.topShare >= cfg.concentratedShare && r.metrics.pixels >= cfg.concentratedMinPixels)
    r.flags.push_back(fmt::format("concentrated:{:.0f}% of the error in {} pixels{}", 100 * r.metrics.topShare,
                                  kTopPixels, worstPixelText(r)));
}

}  // namespace

StabilityReport analyzeStability(std::vector<RunRecord>& runs, const std::map<std::string, ReferenceNoise>& refNoise,
                                 const StabilityConfig& cfg) {
  std::map<GroupKey, std::vector<RunRecord*>> groups;
  std::vector<std::pair<std::string, std::string>> pairs;  // (scene, method) in order of appearance
  for (RunRecord& r : runs) {
    r.flags.clear();
    groups[{r.scene, r.method, r.budgetIndex}].push_back(&r);
    if (std::find(pairs.begin(), pairs.end(), std::make_pair(r.scene, r.method)) == pairs.end())
      pairs.emplace_back(r.scene, r.method);
  }
  for (auto& [key, g] : groups) {
    flagOutliers(g, cfg);
    flagBrightness(g, cfg);
    for (RunRecord* r : g) {
      flagStuck(*r, cfg);
      flagConcentrated(*r, cfg);
    }
  }

  StabilityReport report;
  const double nPairs = double(pairs.size());
  for (const auto& [scene, method] : pairs) {
    MethodVerdict v;
    v.scene = scene;
    v.method = method;
    auto noiseIt = refNoise.find(scene);
    double sigmaRef = noiseIt != refNoise.end() ? noiseIt->second.meanRelStdErr : 0;
    std::vector<double> pValues;
    double wSum = 0, wBias = 0;
    for (auto& [key, g] : groups) {
      if (std::get<0>(key) != scene || std::get<1>(key) != method) continue;
      std::vector<double> m;
      for (RunRecord* r : g) {
        ++v.runs;
        if (r->metrics.nonFinite > 0) ++v.nonFiniteRuns;
        if (hasFlag(*r, "stuck")) ++v.stuckRuns;
        if (hasFlag(*r, "concentrated")) {
          ++v.concentratedRuns;
          v.worstTopShare = std::max(v.worstTopShare, r->metrics.topShare);
        }
        if (hasFlag(*r, "brightness")) ++v.brightnessRuns;
        if (hasFlag(*r, "outlier")) {
          ++v.outlierRuns;
          std::vector<double> err;
          for (RunRecord* o : g) err.push_back(o->metrics.relMSE);
          double med = median(err);
          if (med > 0) v.worstOutlierRatio = std::max(v.worstOutlierRatio, r->metrics.relMSE / med);
        }
        if (std::isfinite(r->metrics.meanErr)) m.push_back(r->metrics.meanErr);
      }
      if (m.size() < 2) continue;
      double n = double(m.size()), mb = mean(m), s = stddev(m);
      double se = std::sqrt(s * s / n + sigmaRef * sigmaRef);
      double p = se > 0 ? studentTwoSidedP(mb / se, n - 1) : (mb == 0 ? 1 : 0);
      pValues.push_back(p);
      if (se > 0) {
        wSum += 1 / (se * se);
        wBias += mb / (se * se);
      }
    }
    if (!pValues.empty()) {
      v.biasP = std::min(1.0, fisherCombine(pValues) * nPairs);  // Bonferroni over (scene, method) pairs
      if (wSum > 0) {
        v.bias = wBias / wSum;
        v.biasStdErr = 1 / std::sqrt(wSum);
      }
      v.biased = v.biasP < cfg.biasAlpha && std::fabs(v.bias) >= cfg.minBias;
    }
    if (v.biased)
      v.problems.push_back(fmt::format("biased: mean brightness {:+.2f}% +- {:.2f}% (p={:.1e}); {}", 100 * v.bias,
                                       100 * v.biasStdErr, v.biasP,
                                       v.bias < 0 ? "missing transport" : "extra energy"));
    if (v.outlierRuns > 0)
      v.problems.push_back(fmt::format("unstable: {} of {} runs are outliers (relMSE up to {:.3g}x the median)",
                                       v.outlierRuns, v.runs, v.worstOutlierRatio));
    if (v.brightnessRuns > 0)
      v.problems.push_back(fmt::format("brightness: {} of {} runs miss or gain transport relative to the others",
                                       v.brightnessRuns, v.runs));
    if (v.stuckRuns > 0)
      v.problems.push_back(fmt::format("stuck chains: {} of {} runs have a path length or chain with "
                                       "acceptance < {:.2g}",
                                       v.stuckRuns, v.runs, cfg.stuckAcceptance));
    if (v.concentratedRuns > 0)
      v.problems.push_back(fmt::format("concentrated error: {} of {} runs hold at least {:.0f}% of their relMSE in "
                                       "{} pixels (up to {:.0f}%: a chain confined to them, or a firefly)",
                                       v.concentratedRuns, v.runs, 100 * cfg.concentratedShare, kTopPixels,
                                       100 * v.worstTopShare));
    if (v.nonFiniteRuns > 0)
      v.problems.push_back(fmt::format("non-finite pixels in {} of {} runs", v.nonFiniteRuns, v.runs));
    report.verdicts.push_back(std::move(v));
  }
  return report;
}

}  // namespace mlt::eval
