// The 1D experiment of Bitterli et al. 2017, Figure 3 / sec. 7.1: Markov chain integration on [0,1] of a
// sinusoid target f with three sampling techniques
//   a: triangular pdf p_a(x) = 2x                     (x = sqrt(u2))
//   b: step pdf p_b = 1.5 on [0, 1/2), 0.5 on [1/2, 1) (inverse CDF)
//   c: a mixture, chosen by u3 < alpha, of p_s(x) = (pi/2) sin(pi x) and p_l(x) = 2 (1 - x)
// Primary samples: u1 technique (MMLT only), u2 position, u3 sub-technique (read by c only). MMLT's target
// on (i, u) is C_i(u) = 3 w_i(x) f(x) / p_i(x) with balance-heuristic weights w_i = p_i / sum_j p_j; its
// stationary density of x is f, and the technique at x is used with probability w_i(x).
// Chains (no large steps, as in the paper, to expose bias):
//   mmlt      small Gaussian steps of (u1, u2, u3): the baseline (Figure 3a);
//   rjmlt     small steps of (u2, u3) with the technique kept apart, plus reversible jumps: j != i chosen
//             uniformly, u' = S_j^-1(S_i(u), gamma), accepted by eq. 38 with |J[S^-1]| = p (eq. 42-44 for
//             the mixture: sub-technique t by T(t) = alpha_t p_t / p_c, u3 uniform in t's interval, eq. 40);
//   noJacobian   the same without the Jacobian ratio of eq. 38 (Figure 3b);
//   fixedPoint   the mixture's ambiguous u3 interval inverted to a fixed point, its start (Figure 3c).
// The test asserts that mmlt and rjmlt reproduce f (and rjmlt the MIS weights as technique usage), and
// that noJacobian and fixedPoint visibly do not. Fixed seeds; statistics over independent chains.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "common/core/rng.h"
#include "common/core/sampling_inverse.h"

namespace mlt {
namespace {

constexpr double kPiD = 3.14159265358979323846;
constexpr double kAlpha = 0.5;  // probability of the sinusoid sub-technique of c
constexpr int kBins = 20;

double f(double x) { return 1 + 0.8 * std::sin(2 * kPiD * x); }
double pA(double x) { return 2 * x; }
double pB(double x) { return x < 0.5 ? 1.5 : 0.5; }
double pS(double x) { return kPiD / 2 * std::sin(kPiD * x); }
double pL(double x) { return 2 * (1 - x); }
double pC(double x) { return kAlpha * pS(x) + (1 - kAlpha) * pL(x); }
double pdf(int i, double x) { return i == 0 ? pA(x) : i == 1 ? pB(x) : pC(x); }

// S_i(u2, u3) -> x.
double sample(int i, double u2, double u3) {
  if (i == 0) return std::sqrt(u2);
  if (i == 1) return u2 < 0.75 ? u2 / 1.5 : 0.5 + (u2 - 0.75) / 0.5;
  if (u3 < kAlpha) return std::acos(1 - 2 * u2) / kPiD;
  return 1 - std::sqrt(1 - u2);
}

// C_i(u) = 3 w_i f / p_i (balance heuristic): the MMLT target of technique i.
double target(int i, double x) {
  const double sum = pA(x) + pB(x) + pC(x);
  const double p = pdf(i, x);
  return p > 0 && sum > 0 ? 3 * (p / sum) * f(x) / p : 0.0;
}

enum class Variant { Full, NoJacobian, FixedPoint };

struct Inverted {
  double u2, u3, jacobian;
};
// S_j^-1(x, gamma): the probabilistic inverse. Jacobian |J[S_j^-1]| = p_j(x) (the mixture's is
// alpha_t p_t / T(t) = p_c, eq. 42 with T of eq. 44 folded in).
Inverted invert(int j, double x, Pcg32& rng, Variant v) {
  const double gammaFill = rng.uniform();
  if (j == 0) return {x * x, gammaFill, pA(x)};  // u3 unread: resampled (eq. 40 on [0,1))
  if (j == 1) return {x < 0.5 ? 1.5 * x : 0.75 + 0.5 * (x - 0.5), gammaFill, pB(x)};
  const float w[2] = {float(kAlpha * pS(x)), float((1 - kAlpha) * pL(x))};
  float rest = 0;
  const int t = pickByWeight(w, 2, rng.uniform(), &rest);  // T(t), eq. 44
  const double g = v == Variant::FixedPoint ? 0.0 : double(rest);  // fixed: the interval's start, as a plain CDF would
  if (t == 0) return {(1 - std::cos(kPiD * x)) / 2, g * kAlpha, pC(x)};  // eq. 41: u3 in [0, alpha)
  return {1 - (1 - x) * (1 - x), kAlpha + g * (1 - kAlpha), pC(x)};     // u3 in [alpha, 1)
}

double wrap(double u) { return u - std::floor(u); }

struct Histograms {
  std::array<double, kBins> x{};
  std::array<std::array<double, 3>, kBins> technique{};
};

// One chain of `steps` steps; every step's state is histogrammed (x and its technique).
Histograms runChain(bool mmlt, Variant variant, uint64_t seed, int steps) {
  Pcg32 rng(seed, 17);
  Histograms h;
  constexpr double sigma = 0.05;
  auto gauss = [&]() {  // Box-Muller
    const double a = std::max(1e-12, double(rng.uniform())), b = rng.uniform();
    return std::sqrt(-2 * std::log(a)) * std::cos(2 * kPiD * b);
  };
  // Start: a state with positive target (every technique covers (0,1)).
  double u1 = 0.5, u2 = 0.5, u3 = 0.25;
  int i = 1;
  double x = sample(i, u2, u3), c = target(i, x);
  for (int n = 0; n < steps; ++n) {
    if (mmlt || rng.uniform() < 0.5f) {  // rjmlt: half the steps are jumps (amplifies a jump's bias)
      const double v1 = mmlt ? wrap(u1 + sigma * gauss()) : u1, v2 = wrap(u2 + sigma * gauss()),
                   v3 = wrap(u3 + sigma * gauss());
      const int j = mmlt ? std::min(2, int(v1 * 3)) : i;
      const double y = sample(j, v2, v3), cy = target(j, y);
      if (rng.uniform() < cy / c) {
        u1 = v1, u2 = v2, u3 = v3, i = j, x = y, c = cy;
      }
    } else {
      // Reversible jump (eq. 38): the path x is kept, the technique changes.
      const int j = (i + 1 + int(rng.uniform() * 2)) % 3;
      const Inverted cur = invert(i, x, rng, variant), inv = invert(j, x, rng, variant);
      const double y = sample(j, inv.u2, inv.u3), cy = target(j, y);
      const double jacobianRatio = variant == Variant::NoJacobian ? 1.0 : inv.jacobian / cur.jacobian;
      if (std::fabs(y - x) < 1e-6 && rng.uniform() < cy * jacobianRatio / c) {
        u2 = inv.u2, u3 = inv.u3, i = j, x = y, c = cy;
      }
    }
    const int bin = std::min(kBins - 1, int(x * kBins));
    h.x[bin] += 1;
    h.technique[bin][i] += 1;
  }
  return h;
}

// Expected fraction of the states in each bin: the normalized integral of f over the bin.
double expectedFraction(int b) {
  const double lo = double(b) / kBins, hi = double(b + 1) / kBins;
  return (hi - lo) + 0.8 * (std::cos(2 * kPiD * lo) - std::cos(2 * kPiD * hi)) / (2 * kPiD);
}

struct Fit {
  double chi2 = 0;          // sum over bins of z^2, z = (mean - expected) / standard error across chains
  double techniqueErr = 0;  // largest |usage - mean MIS weight| over bins and techniques
};

Fit fit(bool mmlt, Variant v) {
  constexpr int kChains = 24, kSteps = 400000;
  std::array<std::vector<double>, kBins> frac;
  std::array<std::array<double, 3>, kBins> usage{};
  std::array<double, kBins> total{};
  for (int ch = 0; ch < kChains; ++ch) {
    const Histograms h = runChain(mmlt, v, 1000 + ch, kSteps);
    for (int b = 0; b < kBins; ++b) {
      frac[b].push_back(h.x[b] / kSteps);
      for (int i = 0; i < 3; ++i) usage[b][i] += h.technique[b][i];
      total[b] += h.x[b];
    }
  }
  Fit r;
  for (int b = 0; b < kBins; ++b) {
    double mean = 0, var = 0;
    for (double q : frac[b]) mean += q / kChains;
    for (double q : frac[b]) var += (q - mean) * (q - mean) / (kChains - 1);
    const double z = (mean - expectedFraction(b)) / std::sqrt(var / kChains + 1e-18);
    r.chi2 += z * z;
    // MIS weight of each technique averaged over the bin (weighted by f).
    std::array<double, 3> w{};
    double wf = 0;
    for (int q = 0; q < 64; ++q) {
      const double x = (b + (q + 0.5) / 64) / kBins, sum = pA(x) + pB(x) + pC(x);
      for (int i = 0; i < 3; ++i) w[i] += f(x) * pdf(i, x) / sum;
      wf += f(x);
    }
    for (int i = 0; i < 3; ++i) r.techniqueErr = std::max(r.techniqueErr, std::fabs(usage[b][i] / total[b] - w[i] / wf));
  }
  return r;
}

// 20 bins: chi-square with 20 dof exceeds 45 with probability 1e-3 (Student-t tails of 24 chains widen it;
// the bound below leaves room for that).
constexpr double kChi2Bound = 60;

TEST(RjmltFigure3, MmltBaselineMatchesTarget) {
  const Fit r = fit(true, Variant::Full);
  std::printf("mmlt:        chi2 %.1f, technique usage error %.3f\n", r.chi2, r.techniqueErr);
  EXPECT_LT(r.chi2, kChi2Bound);
  EXPECT_LT(r.techniqueErr, 0.02);
}

TEST(RjmltFigure3, ReversibleJumpsMatchTargetAndMisWeights) {
  const Fit r = fit(false, Variant::Full);
  std::printf("rjmlt:       chi2 %.1f, technique usage error %.3f\n", r.chi2, r.techniqueErr);
  EXPECT_LT(r.chi2, kChi2Bound);
  EXPECT_LT(r.techniqueErr, 0.02);
}

TEST(RjmltFigure3, DroppingTheJacobianIsBiased) {
  const Fit r = fit(false, Variant::NoJacobian);
  std::printf("no Jacobian: chi2 %.1f, technique usage error %.3f\n", r.chi2, r.techniqueErr);
  EXPECT_GT(r.chi2, 20 * kChi2Bound);
}

TEST(RjmltFigure3, FixedPointInverseOfAmbiguousIntervalIsBiased) {
  const Fit r = fit(false, Variant::FixedPoint);
  std::printf("fixed point: chi2 %.1f, technique usage error %.3f\n", r.chi2, r.techniqueErr);
  EXPECT_GT(r.chi2, 4 * kChi2Bound);
}

}  // namespace
}  // namespace mlt
