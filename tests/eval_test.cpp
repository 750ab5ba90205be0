// The evaluation harness: metrics on synthetic images (exact values), statistics, outlier / bias / stuck
// detection on synthetic runs, CSV round trip, and (see eval_e2e section) the harness end to end on a
// tiny scene with a deliberately biased method and an injected outlier run.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <spdlog/spdlog.h>

#include "common/core/rng.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"
#include "tools/eval/error_map.h"
#include "tools/eval/harness.h"
#include "tools/eval/job_runner.h"
#include "tools/eval/reference.h"
#include "tools/eval/metrics.h"
#include "tools/eval/run_record.h"
#include "tools/eval/stability.h"
#include "tools/eval/stats.h"

namespace mlt::eval {
namespace {

// ---- Metrics -------------------------------------------------------------------------------------------

TEST(EvalMetrics, ExactValuesOnTwoPixels) {
  // Reference (1,1,1), (0,0,0); image (2,1,1), (0.1,0,0). Per channel differences: 1,0,0, 0.1,0,0.
  std::vector<Color> ref{{1, 1, 1}, {0, 0, 0}}, img{{2, 1, 1}, {0.1f, 0, 0}};
  const double eps = 1e-2;
  ImageMetrics m = computeMetrics(img, ref, eps);
  double d2 = double(0.1f) * double(0.1f);
  EXPECT_NEAR(m.relMSE, (1.0 / (1 + eps) + d2 / eps) / 6, 1e-12);
  EXPECT_NEAR(m.mse, (1.0 + d2) / 6, 1e-12);
  EXPECT_NEAR(m.mae, (1.0 + double(0.1f)) / 6, 1e-12);
  EXPECT_NEAR(m.refMean, 0.5, 1e-12);
  EXPECT_NEAR(m.mean, (4.0 + double(0.1f)) / 6, 1e-12);
  EXPECT_NEAR(m.meanErr, ((4.0 + double(0.1f)) / 6 - 0.5) / 0.5, 1e-12);
  EXPECT_EQ(m.nonFinite, 0u);
}

TEST(EvalMetrics, ScaledImageHasExactRelativeBrightnessError) {
  std::vector<Color> ref, img;
  Pcg32 rng(7, 1);
  for (int i = 0; i < 100; ++i) {
    Color c(rng.uniform() + 0.1f, rng.uniform(), rng.uniform() * 3);
    ref.push_back(c);
    img.push_back(c * 1.05f);
  }
  ImageMetrics m = computeMetrics(img, ref);
  EXPECT_NEAR(m.meanErr, 0.05, 1e-6);
  ImageMetrics same = computeMetrics(ref, ref);
  EXPECT_EQ(same.relMSE, 0);
  EXPECT_EQ(same.mse, 0);
  EXPECT_EQ(same.meanErr, 0);
}

// topShare: the share of relMSE in the kTopPixels worst pixels. Noise spread over a 64x64 image leaves a
// few percent there; the same image with one chain's share dumped on 3 adjacent pixels (what a Markov
// chain confined to them does) holds most of its error there.
TEST(EvalMetrics, TopShareSeesErrorConcentratedInAFewPixels) {
  std::vector<Color> ref(64 * 64, Color(0.5f, 0.5f, 0.5f)), noisy = ref;
  Pcg32 rng(3, 1);
  for (Color& c : noisy) c = c * (0.9f + 0.2f * rng.uniform());
  const ImageMetrics spread = computeMetrics(noisy, ref);
  EXPECT_GT(spread.topShare, 0.0);
  EXPECT_LT(spread.topShare, 0.01);  // 4 of 4096 pixels, each at most ~3x the mean error
  std::vector<Color> confined = noisy;
  for (int i = 0; i < 3; ++i) confined[2000 + i] = Color(20, 20, 20);
  confined[2001] = Color(30, 30, 30);
  const ImageMetrics m = computeMetrics(confined, ref);
  EXPECT_EQ(m.worstPixel, 2001u);
  double expectedTop = 0;
  for (double x : {20.0, 30.0, 20.0}) expectedTop += 3 * ((x - 0.5) * (x - 0.5)) / (0.25 + 1e-2);
  // the fourth worst pixel is a noisy one: its share is below 1e-3 of the total
  EXPECT_NEAR(m.topShare, expectedTop / (m.relMSE * 3 * 4096), 1e-3);
  EXPECT_GT(m.topShare, 0.9);
  EXPECT_EQ(computeMetrics(ref, ref).topShare, 0.0);  // an exact image has no error to hold
}

TEST(EvalMetrics, NonFiniteValuesAreCountedAndExcluded) {
  std::vector<Color> ref{{1, 1, 1}, {1, 1, 1}}, img{{1, 1, 1}, {NAN, 1, INFINITY}};
  ImageMetrics m = computeMetrics(img, ref);
  EXPECT_EQ(m.nonFinite, 2u);
  EXPECT_EQ(m.mse, 0);
  EXPECT_THROW(computeMetrics(img, std::vector<Color>(3)), std::invalid_argument);
  auto map = relativeErrorMap(img, ref);
  EXPECT_EQ(map[0], 0.f);
  EXPECT_TRUE(std::isinf(map[1]));
}

TEST(EvalMetrics, ReferenceNoiseFloorMatchesKnownVariance) {
  // K parts = truth + independent Gaussian noise of sigma; the estimated variance of the mean must
  // match sigma^2 / K within its own sampling error (chi-square with P*3*(K-1) dof).
  const int K = 4, P = 4000;
  const double sigma = 0.1;
  std::vector<std::vector<Color>> parts(K, std::vector<Color>(P));
  Pcg32 rng(11, 1);
  auto gauss = [&] {  // Box-Muller
    double u1 = std::max(double(rng.uniform()), 1e-12), u2 = rng.uniform();
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  };
  for (int k = 0; k < K; ++k)
    for (int i = 0; i < P; ++i)
      for (int c = 0; c < 3; ++c) parts[k][i][c] = float(1.0 + sigma * gauss());
  ReferenceEstimate est = estimateReference(parts, 1e-2);
  double expectedMse = sigma * sigma / K;
  double relSe = std::sqrt(2.0 / (3.0 * P * (K - 1)));  // relative std. error of a pooled variance
  EXPECT_NEAR(est.noise.mseFloor / expectedMse, 1.0, 5 * relSe);
  EXPECT_NEAR(est.noise.relMSEFloor, est.noise.mseFloor / (1 + 1e-2), 0.05 * est.noise.mseFloor);
  EXPECT_EQ(est.noise.parts, K);
  EXPECT_GT(est.noise.meanRelStdErr, 0);
  EXPECT_THROW(estimateReference({parts[0]}), std::invalid_argument);
}

// ---- Statistics ----------------------------------------------------------------------------------------

TEST(EvalStats, MomentsAndRobustScale) {
  std::vector<double> x{1, 2, 3, 4, 100};
  EXPECT_DOUBLE_EQ(mean(x), 22);
  EXPECT_DOUBLE_EQ(median(x), 3);
  EXPECT_DOUBLE_EQ(mad(x), 1);
  EXPECT_NEAR(stddev({1, 2, 3}), 1.0, 1e-15);
  EXPECT_THROW(mean({}), std::invalid_argument);
}

TEST(EvalStats, StudentTAndChiSquareTails) {
  // Known quantiles: t(1) is Cauchy, P(|T| > 1) = 0.5; t(5) two-sided 5% point 2.570582; t(10) 1% point 3.169273.
  EXPECT_NEAR(studentTwoSidedP(1.0, 1), 0.5, 1e-10);
  EXPECT_NEAR(studentTwoSidedP(2.570582, 5), 0.05, 1e-6);
  EXPECT_NEAR(studentTwoSidedP(-3.169273, 10), 0.01, 1e-6);
  EXPECT_NEAR(studentTwoSidedP(0, 3), 1.0, 1e-12);
  // chi^2(2): P(X > x) = exp(-x/2); chi^2(4) 5% point 9.487729.
  EXPECT_NEAR(chiSquareUpperEvenDof(3.0, 2), std::exp(-1.5), 1e-14);
  EXPECT_NEAR(chiSquareUpperEvenDof(9.487729, 4), 0.05, 1e-6);
  // Fisher: one p-value combines to itself.
  EXPECT_NEAR(fisherCombine({0.03}), 0.03, 1e-12);
  EXPECT_LT(fisherCombine({0.01, 0.01}), 0.01);
}

// ---- Stability on synthetic runs ---------------------------------------------------------------------

// R runs of one method at two budgets; relMSE ~ base / budget with +-10% noise, mean error ~ N(bias, sd).
std::vector<RunRecord> syntheticRuns(const std::string& method, int R, double bias, double sd, uint64_t seed) {
  std::vector<RunRecord> runs;
  Pcg32 rng(seed, 1);
  for (int bi = 0; bi < 2; ++bi)
    for (int r = 0; r < R; ++r) {
      RunRecord rec;
      rec.scene = "synthetic";
      rec.method = method;
      rec.budgetIndex = bi;
      rec.budget = 1 << bi;
      rec.run = r;
      rec.metrics.relMSE = 0.01 / rec.budget * (0.9 + 0.2 * rng.uniform());
      double u1 = std::max(double(rng.uniform()), 1e-12), u2 = rng.uniform();
      rec.metrics.meanErr = bias + sd * std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
      runs.push_back(rec);
    }
  return runs;
}

TEST(EvalStability, BiasedMethodIsFlaggedUnbiasedIsNot) {
  auto runs = syntheticRuns("good", 6, 0.0, 0.01, 1);
  auto biased = syntheticRuns("scaled", 6, 0.05, 0.01, 2);
  runs.insert(runs.end(), biased.begin(), biased.end());
  StabilityReport rep = analyzeStability(runs, {{"synthetic", ReferenceNoise{4, 1e-4, 1e-4, 0.002}}});
  ASSERT_EQ(rep.verdicts.size(), 2u);
  EXPECT_FALSE(rep.verdicts[0].biased) << rep.verdicts[0].biasP;
  EXPECT_TRUE(rep.verdicts[0].ok());
  EXPECT_TRUE(rep.verdicts[1].biased);
  EXPECT_NEAR(rep.verdicts[1].bias, 0.05, 5 * rep.verdicts[1].biasStdErr);
}

TEST(EvalStability, ReferenceNoiseExplainsSmallBrightnessOffsets) {
  // A 3% offset that the reference's own 2% std. error explains is not called bias.
  auto runs = syntheticRuns("m", 6, 0.03, 0.001, 3);
  StabilityReport noisyRef = analyzeStability(runs, {{"synthetic", ReferenceNoise{4, 0, 0, 0.02}}});
  EXPECT_FALSE(noisyRef.verdicts[0].biased);
  StabilityReport exactRef = analyzeStability(runs, {{"synthetic", ReferenceNoise{4, 0, 0, 0.0}}});
  EXPECT_TRUE(exactRef.verdicts[0].biased);
}

TEST(EvalStability, InjectedOutlierRunIsFlagged) {
  auto runs = syntheticRuns("m", 5, 0.0, 0.01, 4);
  runs[2].metrics.relMSE *= 30;  // budget 0, run 2
  StabilityReport rep = analyzeStability(runs, {});
  int flagged = 0;
  for (const RunRecord& r : runs) flagged += !r.flags.empty();
  EXPECT_EQ(flagged, 1);
  EXPECT_EQ(runs[2].flags.size(), 1u);
  EXPECT_EQ(runs[2].flags[0].rfind("outlier", 0), 0u) << runs[2].flags[0];
  EXPECT_EQ(rep.verdicts[0].outlierRuns, 1);
  EXPECT_FALSE(rep.verdicts[0].ok());
}

TEST(EvalStability, DimRunIsFlaggedForMissingTransport) {
  auto runs = syntheticRuns("m", 8, 0.0, 0.005, 5);
  runs[3].metrics.meanErr = -0.2;  // one run lost a fifth of the light
  analyzeStability(runs, {});
  bool found = false;
  for (const auto& f : runs[3].flags) found |= f.rfind("brightness", 0) == 0;
  EXPECT_TRUE(found);
  for (size_t i = 0; i < runs.size(); ++i) {
    if (i != 3) {
      EXPECT_TRUE(runs[i].flags.empty()) << i << ": " << runs[i].flags[0];
    }
  }
}

TEST(EvalStability, StuckPathLengthIsFlagged) {
  auto runs = syntheticRuns("mmlt", 3, 0.0, 0.01, 6);
  for (RunRecord& r : runs) {
    r.markovChain = true;
    r.proposedPerLength = {0, 0, 50000, 40000};
    r.acceptedPerLength = {0, 0, 20000, 15000};
  }
  runs[1].acceptedPerLength[3] = 2;  // length 3 practically never accepts in run 1
  StabilityReport rep = analyzeStability(runs, {});
  ASSERT_FALSE(runs[1].flags.empty());
  EXPECT_NE(runs[1].flags[0].find("k=3"), std::string::npos) << runs[1].flags[0];
  EXPECT_EQ(rep.verdicts[0].stuckRuns, 1);
  EXPECT_TRUE(runs[0].flags.empty());
}

// A run whose error sits in a few pixels is flagged even when its relMSE is in line with the others (all
// runs of a method can be confined so); the others are not.
TEST(EvalStability, ConcentratedErrorRunIsFlagged) {
  auto runs = syntheticRuns("veach-mlt", 5, 0.0, 0.01, 8);
  for (RunRecord& r : runs) {
    r.metrics.topShare = 0.02;
    r.metrics.pixels = 256 * 256;
  }
  runs[1].metrics.topShare = 0.85;
  runs[1].metrics.worstPixel = 10 * 256 + 3;
  StabilityReport rep = analyzeStability(runs, {});
  ASSERT_EQ(runs[1].flags.size(), 1u);
  EXPECT_EQ(runs[1].flags[0], "concentrated:85% of the error in 4 pixels");  // the film's width unknown
  runs[1].width = 256;
  rep = analyzeStability(runs, {});
  ASSERT_EQ(runs[1].flags.size(), 1u);
  EXPECT_EQ(runs[1].flags[0], "concentrated:85% of the error in 4 pixels, the worst at (3, 10)");
  for (size_t i = 0; i < runs.size(); ++i) {
    if (i != 1) {
      EXPECT_TRUE(runs[i].flags.empty()) << i << ": " << runs[i].flags[0];
    }
  }
  ASSERT_EQ(rep.verdicts.size(), 1u);
  EXPECT_EQ(rep.verdicts[0].concentratedRuns, 1);
  EXPECT_DOUBLE_EQ(rep.verdicts[0].worstTopShare, 0.85);
  EXPECT_FALSE(rep.verdicts[0].ok());
  runs[1].metrics.topShare = 0.29;  // below the threshold (0.3)
  EXPECT_TRUE(analyzeStability(runs, {}).verdicts[0].ok());
  runs[1].metrics.topShare = 0.85;
  runs[1].metrics.pixels = 32 * 32;  // 4 pixels are 0.4% of this image: not a sign of confinement
  EXPECT_TRUE(analyzeStability(runs, {}).verdicts[0].ok());
}

// ---- Tables and maps -----------------------------------------------------------------------------------

TEST(EvalCsv, RunsRoundTrip) {
  auto runs = syntheticRuns("pt,quoted\"name", 2, 0, 0.01, 7);
  runs[0].flags = {"outlier:x", "stuck:k=3"};
  runs[1].markovChain = true;
  runs[1].acceptance = 0.25;
  runs[1].planSeconds = 0.125;
  runs[1].metrics.topShare = 0.625;
  runs[1].metrics.pixels = 65536;
  runs[1].idealRelMSE = 0.0025;
  std::stringstream ss;
  writeRunsCsv(ss, runs);
  auto back = readRunsCsv(ss);
  ASSERT_EQ(back.size(), runs.size());
  EXPECT_EQ(back[0].method, runs[0].method);
  EXPECT_EQ(back[0].flags, runs[0].flags);
  EXPECT_DOUBLE_EQ(back[1].acceptance, 0.25);
  EXPECT_DOUBLE_EQ(back[1].planSeconds, 0.125);
  EXPECT_DOUBLE_EQ(back[1].metrics.topShare, 0.625);
  EXPECT_EQ(back[1].metrics.pixels, 65536u);
  EXPECT_DOUBLE_EQ(back[1].idealRelMSE, 0.0025);
  EXPECT_LT(back[0].idealRelMSE, 0);  // none (a sample method) round-trips as none
  EXPECT_LT(back[0].planSeconds, 0);  // not measured round-trips as not measured
  EXPECT_FALSE(back[0].markovChain);
  EXPECT_NEAR(back[2].metrics.relMSE, runs[2].metrics.relMSE, 1e-8 * runs[2].metrics.relMSE);
  std::stringstream bad("scene,method\n");
  EXPECT_THROW(readRunsCsv(bad), std::runtime_error);
  // A runs.csv written before ideal_relMSE is still read (ideal unknown), and one written before top_share
  // too (top_share 0).
  std::string text = ss.str(), old, before22;
  std::stringstream lines(text);
  for (std::string line; std::getline(lines, line);) {  // drop the last one, then the last three columns
    line = line.substr(0, line.rfind(','));
    before22 += line + "\n";
    line = line.substr(0, line.rfind(','));
    old += line.substr(0, line.rfind(',')) + "\n";
  }
  std::stringstream without22(before22);
  auto back22 = readRunsCsv(without22);
  ASSERT_EQ(back22.size(), runs.size());
  EXPECT_LT(back22[1].idealRelMSE, 0);
  EXPECT_DOUBLE_EQ(back22[1].metrics.topShare, 0.625);
  std::stringstream before(old);
  auto oldBack = readRunsCsv(before);
  ASSERT_EQ(oldBack.size(), runs.size());
  EXPECT_EQ(oldBack[1].metrics.topShare, 0.0);
  EXPECT_EQ(oldBack[1].metrics.pixels, 0u);
  EXPECT_DOUBLE_EQ(oldBack[1].planSeconds, 0.125);
}

TEST(EvalErrorMap, RampIsMonotoneInBrightness) {
  float prev = -1;
  for (int i = 0; i <= 20; ++i) {
    Color c = errorRampSrgb(i / 20.f);
    float y = luminance(c);
    EXPECT_GT(y, prev);
    prev = y;
  }
  auto img = errorMapImage({0.f, 1e-4f, 10.f, INFINITY});
  EXPECT_EQ(luminance(img[0]), luminance(img[1]));  // 0 and 10^-4 are both the bottom of the ramp
  EXPECT_GT(luminance(img[2]), 0.8f);
}

TEST(EvalHarness, MethodSpecs) {
  MethodSpec a = parseMethodSpec("pt");
  EXPECT_EQ(a.label, "pt");
  EXPECT_EQ(a.method, "pt");
  MethodSpec b = parseMethodSpec("pt-biased=pt*1.05");
  EXPECT_EQ(b.label, "pt-biased");
  EXPECT_DOUBLE_EQ(b.testScale, 1.05);
  EXPECT_EQ(parseMethodSpec("mmlt").method, "mmlt");
  EXPECT_THROW(parseMethodSpec("nope"), std::invalid_argument);
  EXPECT_THROW(parseMethodSpec("x=pt*abc"), std::invalid_argument);
  EXPECT_THROW(parseMethodSpec("=pt"), std::invalid_argument);
  const MethodSpec sd = parseMethodSpec("mmlt+separate-direct");
  EXPECT_EQ(sd.method, "mmlt");
  EXPECT_EQ(sd.label, "mmlt+separate-direct");
  EXPECT_EQ(sd.directLight, DirectLight::Separate);
  EXPECT_EQ(parseMethodSpec("mmlt").directLight, DirectLight::Auto);  // the plan decides
  EXPECT_EQ(parseMethodSpec("sd=pssmlt-bdpt+separate-direct*2").directLight, DirectLight::Separate);
  const MethodSpec chains = parseMethodSpec("veach-mlt+direct-in-chains");
  EXPECT_EQ(chains.method, "veach-mlt");
  EXPECT_EQ(chains.directLight, DirectLight::Chains);
  EXPECT_THROW(parseMethodSpec("pt+separate-direct"), std::invalid_argument);  // pt has no direct pass apart
  EXPECT_THROW(parseMethodSpec("pssmlt+direct-in-chains"), std::invalid_argument);
  EXPECT_THROW(parseMethodSpec("pssmlt+separate-direct"), std::invalid_argument);  // its splats carry no length
  // The MIS heuristic: the harness's base unless +mis-balance or +mis-power.
  EXPECT_FALSE(parseMethodSpec("mmlt").heuristic.has_value());
  EXPECT_EQ(parseMethodSpec("mb=mmlt+mis-balance").heuristic, MisHeuristic::Balance);
  EXPECT_EQ(parseMethodSpec("bdpt+mis-power").heuristic, MisHeuristic::Power);
  EXPECT_EQ(parseMethodSpec("rjmlt+separate-direct+mis-balance").directLight, DirectLight::Separate);
  EXPECT_THROW(parseMethodSpec("mmlt+mis-max"), std::invalid_argument);  // neither a modifier nor name:value
  // A method's own parameters, name:value, checked by the method.
  const MethodSpec rel = parseMethodSpec("rel=mmlt+target:relative+target-floor:0.25");
  EXPECT_EQ(rel.label, "rel");
  EXPECT_EQ(rel.method, "mmlt");
  EXPECT_EQ(rel.params, (MethodParams{{"target", "relative"}, {"target-floor", "0.25"}}));
  EXPECT_EQ(parseMethodSpec("rjmlt+separate-direct+technique-step:0.1").directLight, DirectLight::Separate);
  EXPECT_THROW(parseMethodSpec("mmlt+target:brightness"), std::invalid_argument);  // not a choice
  EXPECT_THROW(parseMethodSpec("pt+target:relative"), std::invalid_argument);       // not pt's parameter
  EXPECT_THROW(parseMethodSpec("mmlt+target"), std::invalid_argument);              // no value
  EXPECT_THROW(parseMethodSpec("mmlt+:relative"), std::invalid_argument);           // no name
  EXPECT_NE(runSeed(1, "s", "pt", 0, 0), runSeed(1, "s", "pt", 0, 1));
  EXPECT_NE(runSeed(1, "s", "pt", 0, 0), runSeed(1, "s", "pt", 1, 0));
}

// ---- End to end (quick mode) -------------------------------------------------------------------------
// The harness on the bundled furnace scene (16x16, every pixel the same analytic value) in equal-samples
// mode, so the runs are deterministic: pt, a copy of pt whose images are scaled by 1.05 (must be flagged
// biased), a copy of pt whose run 1 has its error amplified 10x (must be flagged unstable, that run
// only), and pssmlt (exercises the chain statistics). Every label gets its own job seeds.

std::string tempDir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("mltfarm_eval_test_" + name);
  std::filesystem::remove_all(dir);
  return dir.string();
}

EvalConfig quickConfig(const std::string& out) {
  spdlog::set_level(spdlog::level::warn);
  EvalConfig cfg;
  EvalScene es;
  es.name = "furnace";
  es.desc = loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/furnace-sphere.xml");
  cfg.scenes.push_back(std::move(es));
  cfg.base.width = cfg.base.height = 16;
  cfg.base.bootstrapSamples = 10000;
  cfg.reference.spp = 64;
  cfg.reference.parts = 4;
  cfg.cacheReferences = false;
  cfg.runs = 5;
  cfg.equalSamples = true;
  cfg.budgets = {2, 8};
  cfg.outDir = out;
  cfg.charts = false;
  cfg.verbose = false;
  cfg.seed = 20240611;
  return cfg;
}

const MethodVerdict& verdictOf(const EvalResult& r, const std::string& method) {
  for (const MethodVerdict& v : r.stability.verdicts)
    if (v.method == method) return v;
  throw std::runtime_error("no verdict for " + method);
}

TEST(EvalEndToEnd, QuickModeFlagsBiasedMethodAndOutlierRun) {
  const std::string out = tempDir("quick");
  EvalConfig cfg = quickConfig(out);
  for (const char* m : {"pt", "pt-biased=pt*1.05", "pt-outlier=pt", "pssmlt"}) cfg.methods.push_back(parseMethodSpec(m));
  cfg.injectOutlier = OutlierInjection{"pt-outlier", -1, 1, 10.0};
  EvalResult result = runEval(cfg);
  ASSERT_EQ(result.runs.size(), 4u * 2u * 5u);

  const MethodVerdict& pt = verdictOf(result, "pt");
  EXPECT_TRUE(pt.ok()) << pt.problems[0];
  const MethodVerdict& biased = verdictOf(result, "pt-biased");
  EXPECT_TRUE(biased.biased) << "p=" << biased.biasP << " bias=" << biased.bias;
  EXPECT_NEAR(biased.bias, 0.05, 5 * biased.biasStdErr + 5 * result.refs[0].noise.meanRelStdErr);
  EXPECT_EQ(biased.outlierRuns, 0);
  const MethodVerdict& outlier = verdictOf(result, "pt-outlier");
  EXPECT_EQ(outlier.outlierRuns, 2);  // run 1 at both budgets
  EXPECT_FALSE(outlier.biased);
  for (const RunRecord& r : result.runs) {
    bool isOutlier = false;
    for (const auto& f : r.flags) isOutlier |= f.rfind("outlier", 0) == 0;
    EXPECT_EQ(isOutlier, r.method == "pt-outlier" && r.run == 1) << r.method << " run " << r.run;
    if (r.method == "pssmlt") {
      EXPECT_TRUE(r.markovChain);
      EXPECT_GT(r.acceptance, 0);
      EXPECT_LE(r.acceptance, 1);
      EXPECT_GT(r.chains, 0);
      // An ideal chain with the run's mutations on the reference: pssmlt's chains render the whole image
      // here (no pass), and their correlated visits and the reference's own noise put every run above it
      // (2.7-3.8x when this was written).
      EXPECT_GT(r.idealRelMSE, 0);
      EXPECT_LT(r.idealRelMSE, r.metrics.relMSE);
      double idealSum = 0;
      for (double v : r.bandIdeal) idealSum += v;
      EXPECT_NEAR(idealSum, r.idealRelMSE, 1e-9 * r.idealRelMSE);  // the bands split (I1)
    } else {
      EXPECT_FALSE(r.markovChain);
      EXPECT_LT(r.idealRelMSE, 0);
      EXPECT_EQ(r.work, r.budget);  // equal samples: spp = budget
      for (double v : r.bandIdeal) EXPECT_EQ(v, -1);
    }
    double bandSum = 0;
    for (double v : r.bandRelMSE) bandSum += v;
    EXPECT_NEAR(bandSum, r.metrics.relMSE, 1e-9 * r.metrics.relMSE) << r.method << " run " << r.run;  // (B1)
  }
  // The reference's own noise was estimated and is small next to the injected bias.
  EXPECT_EQ(result.refs[0].noise.parts, 4);
  EXPECT_GT(result.refs[0].noise.relMSEFloor, 0);
  EXPECT_LT(result.refs[0].noise.meanRelStdErr, 0.01);

  // Outputs: the tables read back, the summary names the failures, the error maps exist.
  std::ifstream runsCsv(out + "/runs.csv");
  auto back = readRunsCsv(runsCsv);
  EXPECT_EQ(back.size(), result.runs.size());
  std::ifstream acc(out + "/acceptance.csv");
  std::string line;
  int accRows = -1;
  while (std::getline(acc, line)) ++accRows;
  EXPECT_GT(accRows, 0);
  // Per mutation kind: every pssmlt run has its large and small steps, summing to the run's mutations.
  std::ifstream kinds(out + "/kinds.csv");
  std::getline(kinds, line);
  EXPECT_EQ(line, "scene,method,mode,budget_index,budget,run,kind,proposed,accepted");
  std::map<std::string, int> kindRows;
  std::map<int, uint64_t> proposedPerRun;  // key: budget index * 100 + run
  while (std::getline(kinds, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 9u) << line;
    EXPECT_EQ(f[1], "pssmlt") << line;
    ++kindRows[f[6]];
    EXPECT_LE(std::stoull(f[8]), std::stoull(f[7])) << line;
    proposedPerRun[std::stoi(f[3]) * 100 + std::stoi(f[5])] += std::stoull(f[7]);
  }
  EXPECT_EQ(kindRows["large"], 2 * 5);  // 2 budgets x 5 runs
  EXPECT_EQ(kindRows["small"], 2 * 5);
  for (const RunRecord& r : result.runs) {
    if (r.method == "pssmlt") {
      EXPECT_EQ(proposedPerRun[r.budgetIndex * 100 + r.run], r.samples) << r.run;
    }
  }
  std::ifstream summaryFile(out + "/summary.md");
  std::stringstream summary;
  summary << summaryFile.rdbuf();
  EXPECT_NE(summary.str().find("**pt-biased** fails: biased"), std::string::npos) << summary.str();
  EXPECT_NE(summary.str().find("**pt-outlier** fails: unstable"), std::string::npos);
  EXPECT_NE(summary.str().find("### Where the error is"), std::string::npos);
  EXPECT_NE(summary.str().find("| brightest 1% |"), std::string::npos);
  // bands.csv: one row per run and band, the header first, every pssmlt row with its ideal.
  std::ifstream bandsCsv(out + "/bands.csv");
  std::getline(bandsCsv, line);
  EXPECT_EQ(line, "scene,method,budget,run,band,rel_mse,ideal_rel_mse");
  size_t bandRows = 0;
  while (std::getline(bandsCsv, line)) {
    ++bandRows;
    const bool chain = line.find(",pssmlt,") != std::string::npos;
    EXPECT_EQ(line.back() != ',', chain) << line;
  }
  EXPECT_EQ(bandRows, result.runs.size() * size_t(kBands));
  EXPECT_TRUE(std::filesystem::exists(out + "/maps/furnace_pt_error.png"));
  EXPECT_TRUE(std::filesystem::exists(out + "/maps/furnace_reference.png"));
}

TEST(EvalEndToEnd, ChartScriptWritesCharts) {
  if (std::system("/usr/bin/python3 -c 'import matplotlib' 2>/dev/null") != 0)
    GTEST_SKIP() << "/usr/bin/python3 with matplotlib is not available";
  const std::string out = tempDir("charts");
  EvalConfig cfg = quickConfig(out);
  cfg.runs = 3;
  cfg.methods = {parseMethodSpec("pt"), parseMethodSpec("pssmlt")};
  cfg.charts = true;
  cfg.errorMaps = false;
  runEval(cfg);
  for (const char* f : {"error_time_furnace.png", "spread_furnace.png", "acceptance_furnace.png"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + f)) << f;
  std::ifstream summaryFile(out + "/summary.md");
  std::stringstream summary;
  summary << summaryFile.rdbuf();
  EXPECT_NE(summary.str().find("](error_time_furnace.png)"), std::string::npos);
}

TEST(EvalEndToEnd, ReferenceIsCachedByContentAndSettings) {
  spdlog::set_level(spdlog::level::warn);
  SceneDesc desc = loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/furnace-sphere.xml");
  desc.camera.width = desc.camera.height = 8;
  auto scene = RenderScene::build(desc);
  RenderSettings base;
  base.width = base.height = 8;
  ReferenceSettings rs;
  rs.spp = 8;
  rs.parts = 2;
  const std::string dir = tempDir("refcache");
  const std::string hash = sceneContentHash(desc);
  Reference first = obtainReference(*scene, base, rs, "furnace", hash, dir, 1e-2, 1);
  Reference second = obtainReference(*scene, base, rs, "furnace", hash, dir, 1e-2, 1);
  EXPECT_FALSE(first.info.cached);
  EXPECT_TRUE(second.info.cached);
  ASSERT_EQ(first.image.size(), second.image.size());
  for (size_t i = 0; i < first.image.size(); ++i) EXPECT_EQ(first.image[i].g, second.image[i].g);
  EXPECT_NEAR(second.info.noise.relMSEFloor, first.info.noise.relMSEFloor, 1e-6 * first.info.noise.relMSEFloor);
  // Other settings, other key.
  ReferenceSettings more = rs;
  more.spp = 16;
  EXPECT_NE(referenceCacheKey(hash, base, rs), referenceCacheKey(hash, base, more));
  EXPECT_FALSE(obtainReference(*scene, base, more, "furnace", hash, dir, 1e-2, 1).info.cached);
}

TEST(EvalEndToEnd, EqualTimeModeCalibratesWork) {
  // Structure only (no assertion on speed): calibrated runs ask for positive work and record their time.
  const std::string out = tempDir("time");
  EvalConfig cfg = quickConfig(out);
  cfg.equalSamples = false;
  cfg.runs = 2;
  cfg.budgets = {0.1, 0.3};
  cfg.errorMaps = false;
  cfg.methods = {parseMethodSpec("pt")};
  EvalResult r = runEval(cfg);
  ASSERT_EQ(r.runs.size(), 4u);
  for (const RunRecord& run : r.runs) {
    EXPECT_GE(run.work, 1);
    EXPECT_GT(run.seconds, 0);
    EXPECT_GT(run.samples, 0u);
  }
}

}  // namespace
}  // namespace mlt::eval
