#include "tests/support/chi2.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace mlt::test {

// ---------------------------------------------------------------------------------------------------
// Incomplete gamma function (Numerical Recipes, 3rd ed., sec. 6.2: series for x < a + 1, Lentz's
// continued fraction otherwise).
// ---------------------------------------------------------------------------------------------------
namespace {
double gammaPSeries(double a, double x) {
  double ap = a, sum = 1.0 / a, del = sum;
  for (int n = 0; n < 100000; ++n) {
    ap += 1;
    del *= x / ap;
    sum += del;
    if (std::fabs(del) < std::fabs(sum) * 1e-15) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

double gammaQContinuedFraction(double a, double x) {
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::fabs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1) < 1e-15) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}
}  // namespace

double regularizedGammaQ(double a, double x) {
  if (x <= 0) return 1.0;
  if (x < a + 1) return 1.0 - gammaPSeries(a, x);
  return gammaQContinuedFraction(a, x);
}

double chi2SurvivalProbability(double stat, int dof) {
  if (dof <= 0) return 1.0;
  return regularizedGammaQ(0.5 * dof, 0.5 * stat);
}

// ---------------------------------------------------------------------------------------------------
// Adaptive Simpson quadrature (absolute tolerance, Richardson-corrected), nested for 2D.
// ---------------------------------------------------------------------------------------------------
namespace {
constexpr int kMaxDepth = 10;
// Forced uniform subdivision per dimension so that peaks narrower than the bin are not skipped: a peak
// wider than about 1/16 of a bin's side is always seen. (A missed peak makes the test fail, not pass.)
constexpr int kInitialSplits = 8;

double simpsonRecursive(const std::function<double(double)>& f, double a, double b, double fa, double fm,
                        double fb, double whole, double eps, int depth) {
  const double m = 0.5 * (a + b);
  const double lm = 0.5 * (a + m), rm = 0.5 * (m + b);
  const double flm = f(lm), frm = f(rm);
  const double left = (m - a) / 6 * (fa + 4 * flm + fm);
  const double right = (b - m) / 6 * (fm + 4 * frm + fb);
  const double delta = left + right - whole;
  if (depth <= 0 || std::fabs(delta) <= 15 * eps) return left + right + delta / 15;
  return simpsonRecursive(f, a, m, fa, flm, fm, left, 0.5 * eps, depth - 1) +
         simpsonRecursive(f, m, b, fm, frm, fb, right, 0.5 * eps, depth - 1);
}

double adaptiveSimpson(const std::function<double(double)>& f, double a, double b, double eps) {
  double total = 0;
  const double h = (b - a) / kInitialSplits;
  double fa = f(a);
  for (int i = 0; i < kInitialSplits; ++i) {
    const double x0 = a + i * h, x1 = (i + 1 == kInitialSplits) ? b : a + (i + 1) * h;
    const double fm = f(0.5 * (x0 + x1)), fb = f(x1);
    const double whole = (x1 - x0) / 6 * (fa + 4 * fm + fb);
    total += simpsonRecursive(f, x0, x1, fa, fm, fb, whole, eps / kInitialSplits, kMaxDepth);
    fa = fb;
  }
  return total;
}
}  // namespace

double adaptiveSimpson2D(const std::function<double(double, double)>& f, double x0, double x1, double y0,
                         double y1, double eps) {
  const double innerEps = 0.5 * eps / std::max(x1 - x0, 1e-300);
  auto inner = [&](double x) { return adaptiveSimpson([&](double y) { return f(x, y); }, y0, y1, innerEps); };
  return adaptiveSimpson(inner, x0, x1, 0.5 * eps);
}

// ---------------------------------------------------------------------------------------------------
// The test on a rectangle of (x, y) bins; the sphere version maps directions to (cos theta, phi).
// ---------------------------------------------------------------------------------------------------
namespace {
Chi2Result runChi2(const std::function<std::optional<Vec2>(Pcg32&)>& sample,
                   const std::function<double(double, double)>& density, double x0, double x1, double y0,
                   double y1, int xBins, int yBins, int samples, double significance, int testCount,
                   uint64_t seed, const char* xName, const char* yName) {
  Chi2Result res;
  std::ostringstream msg;
  const int nBins = xBins * yBins;
  std::vector<double> observed(nBins + 1, 0.0), expected(nBins + 1, 0.0);  // last: absorbed
  const double dx = (x1 - x0) / xBins, dy = (y1 - y0) / yBins;

  // Histogram.
  Pcg32 rng(seed, 0x6368693273ULL);
  for (int i = 0; i < samples; ++i) {
    const std::optional<Vec2> p = sample(rng);
    if (!p) {
      observed[nBins] += 1;
      continue;
    }
    const double tolX = 1e-6 * (x1 - x0), tolY = 1e-6 * (y1 - y0);  // float rounding at the edges
    if (!(p->x >= x0 - tolX && p->x <= x1 + tolX && p->y >= y0 - tolY && p->y <= y1 + tolY)) {
      msg << "sample " << i << " outside the domain: (" << p->x << ", " << p->y << ")";
      res.message = msg.str();
      return res;
    }
    const int ix = std::clamp(int((p->x - x0) / dx), 0, xBins - 1);
    const int iy = std::clamp(int((p->y - y0) / dy), 0, yBins - 1);
    observed[iy * xBins + ix] += 1;
  }

  // Expected counts. A coarse Simpson estimate E0 of each bin sets its tolerance: the count error may be
  // 1% of the Poisson noise sqrt(E0) (chi-square contribution <= 1e-4 per bin). An absolute tolerance
  // alone would chase float rounding noise of peaked densities forever.
  double integral = 0;
  for (int iy = 0; iy < yBins; ++iy)
    for (int ix = 0; ix < xBins; ++ix) {
      const double bx0 = x0 + ix * dx, bx1 = x0 + (ix + 1) * dx, by0 = y0 + iy * dy, by1 = y0 + (iy + 1) * dy;
      double coarse = 0;
      for (int a = 0; a <= 4; ++a)
        for (int b = 0; b <= 4; ++b) {
          const double wa = (a == 0 || a == 4) ? 1 : (a % 2 ? 4 : 2), wb = (b == 0 || b == 4) ? 1 : (b % 2 ? 4 : 2);
          coarse += wa * wb * density(bx0 + a * dx / 4, by0 + b * dy / 4);
        }
      coarse *= dx * dy / 144;
      const double eps = 0.01 * std::sqrt(std::max(1.0, std::fabs(coarse) * samples)) / samples;
      const double v = adaptiveSimpson2D(density, bx0, bx1, by0, by1, eps);
      integral += v;
      expected[iy * xBins + ix] = v * samples;
    }
  if (integral > 1 + 1e-3) {
    msg << "density integrates to " << integral << " > 1 over the domain";
    res.message = msg.str();
    return res;
  }
  expected[nBins] = std::max(0.0, 1 - integral) * samples;

  // A sample where the density is (numerically) zero is a definite failure.
  for (int i = 0; i <= nBins; ++i) {
    if (observed[i] > 0 && expected[i] < 1e-9 * samples) {
      if (i == nBins)
        msg << observed[i] << " samples absorbed but the density integrates to " << integral;
      else
        msg << observed[i] << " samples in bin (" << xName << " " << i % xBins << ", " << yName << " "
            << i / xBins << ") whose expected count is " << expected[i];
      res.message = msg.str();
      return res;
    }
  }

  // Pool small bins into one cell; if that cell is still small, fold it into the smallest large bin.
  struct Cell { double obs, exp; int index; };
  std::vector<Cell> cells;
  Cell pool{0, 0, -1};
  for (int i = 0; i <= nBins; ++i) {
    if (expected[i] < 5) {
      pool.obs += observed[i];
      pool.exp += expected[i];
    } else {
      cells.push_back({observed[i], expected[i], i});
    }
  }
  if (pool.exp >= 5 || cells.empty()) {
    cells.push_back(pool);
  } else if (pool.obs > 0 || pool.exp > 0) {
    auto smallest = std::min_element(cells.begin(), cells.end(), [](const Cell& a, const Cell& b) { return a.exp < b.exp; });
    smallest->obs += pool.obs;
    smallest->exp += pool.exp;
  }

  double stat = 0;
  const Cell* worst = nullptr;
  double worstTerm = -1;
  for (const Cell& c : cells) {
    if (c.exp <= 0) continue;
    const double term = (c.obs - c.exp) * (c.obs - c.exp) / c.exp;
    stat += term;
    if (term > worstTerm) { worstTerm = term; worst = &c; }
  }
  res.statistic = stat;
  res.dof = int(cells.size()) - 1;
  res.pValue = chi2SurvivalProbability(stat, res.dof);
  const double alpha = 1 - std::pow(1 - significance, 1.0 / std::max(1, testCount));
  res.passed = res.dof > 0 && res.pValue > alpha;
  msg << "chi2 = " << stat << ", dof = " << res.dof << ", p = " << res.pValue << " (threshold " << alpha
      << "), density integral = " << integral << ", absorbed " << observed[nBins] << "/" << samples;
  if (res.dof <= 0) msg << "; too few cells to test";
  if (worst) {
    msg << "; worst cell ";
    if (worst->index < 0) msg << "(pooled)";
    else if (worst->index == nBins) msg << "(absorbed)";
    else msg << "(" << xName << " " << worst->index % xBins << ", " << yName << " " << worst->index / xBins << ")";
    msg << " observed " << worst->obs << " expected " << worst->exp;
  }
  res.message = msg.str();
  return res;
}
}  // namespace

Chi2Result chi2TestSphere(const std::function<std::optional<Vec3>(Pcg32&)>& sample,
                          const std::function<double(const Vec3&)>& pdfW, int thetaBins, int phiBins,
                          int samples, double significance, int testCount, uint64_t seed) {
  bool badDirection = false;
  Vec3 bad;
  auto toParams = [&](Pcg32& rng) -> std::optional<Vec2> {
    const std::optional<Vec3> w = sample(rng);
    if (!w) return std::nullopt;
    if (!isFinite(*w) || std::fabs(lengthSquared(*w) - 1) > 1e-3f) {
      badDirection = true;
      bad = *w;
      return Vec2(1e30f, 1e30f);  // outside the domain: fails the test
    }
    const float z = std::clamp(w->z, -1.0f, 1.0f);
    float phi = std::atan2(w->y, w->x);
    if (phi < 0) phi += 2 * kPi;
    return Vec2(z, phi);
  };
  // Solid angle d omega = d(cos theta) d phi, so pdfW is already the density in (cos theta, phi).
  auto density = [&](double z, double phi) {
    const double s = std::sqrt(std::max(0.0, 1 - z * z));
    return pdfW(Vec3(float(s * std::cos(phi)), float(s * std::sin(phi)), float(z)));
  };
  Chi2Result r = runChi2(toParams, density, -1, 1, 0, 2 * M_PI, thetaBins, phiBins, samples, significance,
                         testCount, seed, "cos-theta bin", "phi bin");
  if (badDirection) {
    std::ostringstream m;
    m << "sampler returned a non-unit direction (" << bad.x << ", " << bad.y << ", " << bad.z << "); " << r.message;
    r.passed = false;
    r.message = m.str();
  }
  return r;
}

Chi2Result chi2Test2D(const std::function<std::optional<Vec2>(Pcg32&)>& sample,
                      const std::function<double(Vec2)>& pdf, Vec2 lo, Vec2 hi, int xBins, int yBins, int samples,
                      double significance, int testCount, uint64_t seed) {
  auto density = [&](double x, double y) { return pdf(Vec2(float(x), float(y))); };
  return runChi2(sample, density, lo.x, hi.x, lo.y, hi.y, xBins, yBins, samples, significance, testCount, seed,
                 "x bin", "y bin");
}

}  // namespace mlt::test
