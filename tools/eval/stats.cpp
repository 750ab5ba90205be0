#include "tools/eval/stats.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mlt::eval {

namespace {
void requireNonEmpty(const std::vector<double>& x, const char* what) {
  if (x.empty()) throw std::invalid_argument(std::string(what) + ": empty input");
}
}  // namespace

double mean(const std::vector<double>& x) {
  requireNonEmpty(x, "mean");
  double s = 0;
  for (double v : x) s += v;
  return s / double(x.size());
}

double stddev(const std::vector<double>& x) {
  requireNonEmpty(x, "stddev");
  if (x.size() < 2) return 0;
  double m = mean(x), s2 = 0;
  for (double v : x) s2 += (v - m) * (v - m);
  return std::sqrt(s2 / double(x.size() - 1));
}

double median(std::vector<double> x) {
  requireNonEmpty(x, "median");
  std::sort(x.begin(), x.end());
  size_t n = x.size();
  return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

double mad(const std::vector<double>& x) {
  double m = median(x);
  std::vector<double> d;
  d.reserve(x.size());
  for (double v : x) d.push_back(std::fabs(v - m));
  return median(d);
}

// Continued fraction for I_x(a, b) (Numerical Recipes 6.4, modified Lentz's method).
static double betaContinuedFraction(double a, double b, double x) {
  const double tiny = 1e-300, epsilon = 1e-15;
  double qab = a + b, qap = a + 1, qam = a - 1;
  double c = 1, d = 1 - qab * x / qap;
  if (std::fabs(d) < tiny) d = tiny;
  d = 1 / d;
  double h = d;
  for (int m = 1; m <= 500; ++m) {
    int m2 = 2 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1 + aa * d;
    if (std::fabs(d) < tiny) d = tiny;
    c = 1 + aa / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1 + aa * d;
    if (std::fabs(d) < tiny) d = tiny;
    c = 1 + aa / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1 / d;
    double del = d * c;
    h *= del;
    if (std::fabs(del - 1) < epsilon) break;
  }
  return h;
}

double incompleteBeta(double a, double b, double x) {
  if (!(a > 0) || !(b > 0)) throw std::invalid_argument("incompleteBeta: a and b must be positive");
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  double lnFront = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  double front = std::exp(lnFront);
  // Use the symmetry I_x(a,b) = 1 - I_{1-x}(b,a) where the continued fraction converges faster.
  if (x < (a + 1) / (a + b + 2)) return front * betaContinuedFraction(a, b, x) / a;
  return 1 - front * betaContinuedFraction(b, a, 1 - x) / b;
}

double studentTwoSidedP(double t, double dof) {
  if (!(dof > 0)) throw std::invalid_argument("studentTwoSidedP: dof must be positive");
  if (std::isnan(t)) return 1;
  if (std::isinf(t)) return 0;
  return incompleteBeta(0.5 * dof, 0.5, dof / (dof + t * t));
}

double chiSquareUpperEvenDof(double x, int dof) {
  if (dof <= 0 || dof % 2) throw std::invalid_argument("chiSquareUpperEvenDof: dof must be positive and even");
  if (x <= 0) return 1;
  int k = dof / 2;
  double half = 0.5 * x, term = 1, sum = 1;
  for (int i = 1; i < k; ++i) {
    term *= half / i;
    sum += term;
  }
  // exp(-x/2) * sum, computed in logs to avoid 0 * inf for large x.
  return std::min(1.0, std::exp(-half + std::log(sum)));
}

double fisherCombine(const std::vector<double>& pValues) {
  requireNonEmpty(pValues, "fisherCombine");
  double X = 0;
  for (double p : pValues) X += -2 * std::log(std::max(p, 1e-300));
  return chiSquareUpperEvenDof(X, 2 * int(pValues.size()));
}

}  // namespace mlt::eval
