// The chain loop as a 1D canonical integrator: target density p(x) = 1 + 0.9 sin(2 pi x) on [0,1]
// (integral b = 1), read from coordinate 0 of the camera stream of a KelemenSource.
//  - State distribution: many independent chains, each started from a bootstrap candidate drawn in
//    proportion to p (importance resampling from 10^6 candidates, as the renderer does), run for T
//    mutations; their final states (independent across chains) must pass a chi-square test against p,
//    for each kernel, with and without large steps. A chain with a deliberately wrong acceptance ratio
//    a = min(1, sqrt(c(y)/c(x))) (stationary density ~ sqrt(p)) must fail the same test.
//  - Estimator: the developed splat histogram (develop.h (D1)) estimates the bin means of p, for both
//    splatting schemes, within 4 standard errors measured across independent chains.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/mlt/bootstrap.h"
#include "common/mlt/chain.h"
#include "common/mlt/develop.h"
#include "common/mlt/kelemen_source.h"
#include "common/mlt/pss_chain.h"
#include "common/mlt/target.h"
#include "tests/support/chi2.h"

namespace mlt {
namespace {

constexpr uint64_t kSeed = 20240601;
constexpr double kTwoPi = 6.283185307179586;

double density(double x) { return 1 + 0.9 * std::sin(kTwoPi * x); }
double cdf(double x) { return x + 0.9 * (1 - std::cos(kTwoPi * x)) / kTwoPi; }

// c(x) = luminance(Color(p(x))) = p(x) up to the float rounding of the luminance weights; the chi-square
// expectations use the same function.
class OneDTarget final : public ChainTarget {
 public:
  explicit OneDTarget(SampleSource& source) : source_(source) {}
  void evaluate(PathContribution& out) override {
    source_.startStream(Stream::Camera);
    const float x = source_.next1D();
    out.splats.push_back({Vec2(x, 0.5f), Color(float(density(x)))});
  }

 private:
  SampleSource& source_;
};

struct Starts {
  BootstrapResult boot;
  uint64_t candidate(uint64_t chain, uint64_t chains) const {
    Pcg32 rng = chainRng(kSeed, chain, 2);
    return boot.lengths[0].table.sample((double(chain) + rng.uniformDouble()) / double(chains));
  }
};

const Starts& starts() {
  static const Starts s = [] {
    Starts st;
    BootstrapConfig bc;
    bc.candidatesPerLength = 1000000;
    st.boot = runBootstrap(bc, [] {
      return [](uint64_t i, int) { return targetFunction(Color(float(density(IndependentSource::candidate(kSeed, i).valueAt(0, 0))))); };
    });
    return st;
  }();
  return s;
}

class NullSink final : public ChainSink {
 public:
  void splat(const PathContribution&, double) override {}
};

// Final states of `chains` independent chains of `mutations` steps each.
std::vector<double> finalStates(const KelemenParams& params, int chains, uint64_t mutations, double acceptancePower) {
  std::vector<double> xs;
  PathContribution current, scratch;
  NullSink sink;
  ChainConfig config;
  config.acceptancePower = acceptancePower;
  for (int j = 0; j < chains; ++j) {
    KelemenSource source(params, kSeed, j, starts().candidate(j, chains));
    OneDTarget target(source);
    current.clear();
    target.evaluate(current);
    source.accept();
    PssState state(source);
    Pcg32 acceptRng = chainRng(kSeed, j, 1);
    runChain(state, target, config, sink, acceptRng, mutations, current, targetFunction(current), scratch);
    xs.push_back(current.splats[0].pRaster.x);
  }
  return xs;
}

// Chi-square of a 1D sample against p with `bins` equal bins (expected counts >= 5 for these sizes).
double chi2PValue(const std::vector<double>& xs, int bins) {
  std::vector<double> count(bins, 0);
  for (double x : xs) count[std::min(bins - 1, int(x * bins))] += 1;
  double stat = 0;
  for (int i = 0; i < bins; ++i) {
    const double e = double(xs.size()) * (cdf(double(i + 1) / bins) - cdf(double(i) / bins));
    stat += (count[i] - e) * (count[i] - e) / e;
  }
  return test::chi2SurvivalProbability(stat, bins - 1);
}

struct Case {
  const char* name;
  SmallStepKernel kernel;
  float largeStepProb;
  uint64_t mutations;
};

// Six tests (4 correct chains, power 1) share a Sidak-corrected level of 1%.
const double kAlpha = 1 - std::pow(1 - 0.01, 1.0 / 4);

TEST(MltChain1D, StateHistogramMatchesTargetForEachKernel) {
  const Case cases[] = {{"kelemen, large steps", SmallStepKernel::Kelemen, 0.3f, 200},
                        {"kelemen, small steps only", SmallStepKernel::Kelemen, 0.0f, 1000},
                        {"gaussian, large steps", SmallStepKernel::Gaussian, 0.3f, 200},
                        {"gaussian, small steps only", SmallStepKernel::Gaussian, 0.0f, 1000}};
  for (const Case& c : cases) {
    KelemenParams params;
    params.kernel = c.kernel;
    params.largeStepProb = c.largeStepProb;
    params.sigma = 0.01f;
    const std::vector<double> xs = finalStates(params, 20000, c.mutations, 1.0);
    const double p = chi2PValue(xs, 50);
    EXPECT_GT(p, kAlpha) << c.name << ": chi-square p-value " << p;
  }
}

TEST(MltChain1D, WrongAcceptanceRatioFails) {
  KelemenParams params;
  params.largeStepProb = 0.3f;
  const std::vector<double> xs = finalStates(params, 20000, 200, 0.5);
  const double p = chi2PValue(xs, 50);
  EXPECT_LT(p, 1e-6) << "a chain sampling sqrt(p) passed the chi-square test against p (p-value " << p << ")";
  // Sanity: the same chains sample sqrt(p)'s shape, i.e. the density at the peak is lower than p's.
  int nearPeak = 0;
  for (double x : xs) nearPeak += (x > 0.2 && x < 0.3);
  const double expected = 20000 * (cdf(0.3) - cdf(0.2));
  EXPECT_LT(nearPeak, expected - 5 * std::sqrt(expected));
}

// Splat estimator: bins of width 1/B; developed value of bin i = b * B / M * splatSum_i estimates the
// mean of p over the bin. Chains are independent, so their per-chain estimates give a standard error.
// weightBFactor: Kelemen MIS weights with b times this (a bootstrap's b that missed), its large steps in
// layer 1 developed with that b (chain.h (K1)); oneLayer: the large steps' share in layer 0 with the rest
// (what a sink without a large-step layer does), expected to fail where the factor is not 1.
// Returns how many bins missed the exact value by more than the tolerance.
int estimatorMisses(ChainSplatting splatting, float largeStepProb, double weightBFactor = 1, bool oneLayer = false) {
  const int B = 10, chains = 64;
  const uint64_t mutations = 20000;
  KelemenParams params;
  params.largeStepProb = largeStepProb;
  const double b = starts().boot.b;
  std::vector<double> sum(B, 0), sumSq(B, 0);
  int misses = 0;
  for (int j = 0; j < chains; ++j) {
    Film film(B, 1);
    KelemenSource source(params, kSeed, 1000 + j, starts().candidate(j, chains));
    // Splat raster x in [0, B): rescale the 1D target's x in [0, 1).
    class Scaled final : public ChainTarget {
     public:
      Scaled(SampleSource& s, int B) : inner_(s), B_(B) {}
      void evaluate(PathContribution& out) override {
        inner_.evaluate(out);
        for (Splat& sp : out.splats) sp.pRaster.x *= float(B_);
      }
      OneDTarget inner_;
      int B_;
    } target(source, B);
    PathContribution current, scratch;
    target.evaluate(current);
    source.accept();
    PssState state(source);
    FilmSink sink(film, 0, oneLayer ? 0 : 1);
    ChainConfig config;
    config.splatting = splatting;
    config.largeStepProb = largeStepProb;
    config.b = b * weightBFactor;
    Pcg32 acceptRng = chainRng(kSeed, 1000 + j, 1);
    runChain(state, target, config, sink, acceptRng, mutations, current, targetFunction(current), scratch);
    const std::vector<Color> img = film.develop(std::vector<double>{
        chainSplatScale(b, mutations, film.pixelCount()), chainSplatScale(config.b, mutations, film.pixelCount())});
    for (int i = 0; i < B; ++i) {
      sum[i] += img[i].r;
      sumSq[i] += double(img[i].r) * img[i].r;
    }
  }
  for (int i = 0; i < B; ++i) {
    const double mean = sum[i] / chains;
    const double se = std::sqrt(std::max(0.0, sumSq[i] / chains - mean * mean) / (chains - 1));
    const double exact = B * (cdf(double(i + 1) / B) - cdf(double(i) / B));
    // 4 standard errors (10 bins x 4 configurations: a false alarm rate of ~2.5e-3 in all), plus the
    // bootstrap's relative error on b (the same factor for every chain).
    const double tol = 4 * se + 4 * starts().boot.bStdErr * exact;
    if (!(std::fabs(mean - exact) <= tol)) ++misses;
    if (!oneLayer)
      EXPECT_NEAR(mean, exact, tol) << "bin " << i << " (splatting " << int(splatting) << ", p_large "
                                    << largeStepProb << ", weights' b x " << weightBFactor << "), standard error " << se;
  }
  return misses;
}

TEST(MltChain1D, ExpectedValueSplattingEstimatesBinMeans) {
  estimatorMisses(ChainSplatting::ExpectedValue, 0.3f);
  estimatorMisses(ChainSplatting::ExpectedValue, 0.0f);
}

TEST(MltChain1D, KelemenMisSplattingEstimatesBinMeans) {
  estimatorMisses(ChainSplatting::KelemenMIS, 0.3f);
  estimatorMisses(ChainSplatting::KelemenMIS, 0.8f);
}

// The b in Kelemen's weights is the bootstrap's, never exact. With the large steps' share developed with
// that same b (chain.h (K1)) the bins stay right when it is off by a factor 2 either way; developed with
// the true b, in one layer with the rest, the same chains miss most bins (in the dark bins by up to
// p (b - b_w) / (c + b_w p): 0.8 * 0.5 / (0.1 + 0.4) = 80% at b_w = b / 2).
TEST(MltChain1D, KelemenMisStaysRightWhenTheWeightsBIsOff) {
  for (double factor : {0.5, 2.0}) estimatorMisses(ChainSplatting::KelemenMIS, 0.8f, factor);
  EXPECT_GE(estimatorMisses(ChainSplatting::KelemenMIS, 0.8f, 0.5, /*oneLayer=*/true), 5)
      << "one layer developed with the true b should be biased: the test cannot tell the layers apart";
}

TEST(MltChain1D, BootstrapEstimatesB) {
  const BootstrapResult& boot = starts().boot;
  const double iidStdErr = std::sqrt(0.405 / 1e6);  // standard error of the mean of N i.i.d. p(U): sqrt(0.9^2 / 2 / N)
  EXPECT_NEAR(boot.b, 1.0, 4 * boot.bStdErr + 1e-6);
  // A candidate alone is a uniform sample: the variance of p(U), 0.9^2 / 2.
  EXPECT_NEAR(boot.lengths[0].estimate.sampleVar, 0.405, 0.05 * 0.405);
  // The candidates' coordinate 0 is spread evenly (a randomized Halton sequence): for this smooth density the
  // mean is far more precise than from i.i.d. samples, and the group-based standard error says so.
  EXPECT_LT(boot.bStdErr, 0.1 * iidStdErr);
  EXPECT_NEAR(boot.b, 1.0, 0.1 * iidStdErr);
}

}  // namespace
}  // namespace mlt
