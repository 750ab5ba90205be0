#include "tools/eval/ideal_chain.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace mlt::eval {

namespace {

// a_j of (I1): the pixel's relMSE weight, averaged over channels.
double pixelWeight(const Color& I, double eps) {
  const double ch[3] = {I.r, I.g, I.b};
  double a = 0;
  for (double x : ch) a += x * x / (x * x + eps);
  return a / 3;
}

// c_j = L_j, the luminance target (negative luminance, which no renderer here produces, counts as 0).
std::vector<double> luminanceTarget(const std::vector<Color>& reference) {
  std::vector<double> lum(reference.size());
  for (size_t j = 0; j < reference.size(); ++j) lum[j] = std::fmax(0.0, double(luminance(reference[j])));
  return lum;
}

}  // namespace

std::vector<double> idealChainTerms(const std::vector<Color>& reference, const std::vector<double>& c,
                                    double mutations, double eps) {
  if (reference.empty()) throw std::invalid_argument("idealChainRelMse: empty reference");
  if (c.size() != reference.size())
    throw std::invalid_argument("idealChainRelMse: " + std::to_string(c.size()) + " target values for " +
                                std::to_string(reference.size()) + " pixels");
  if (!(mutations > 0)) throw std::invalid_argument("idealChainRelMse: mutations must be > 0");
  if (!(eps > 0)) throw std::invalid_argument("idealChainRelMse: eps must be > 0");
  double C = 0;
  for (size_t j = 0; j < c.size(); ++j) {
    if (!(c[j] >= 0) || !std::isfinite(c[j]))
      throw std::invalid_argument("idealChainRelMse: target value " + std::to_string(c[j]) + " at pixel " +
                                  std::to_string(j) + " (must be finite and >= 0)");
    C += c[j];
  }
  if (!(C > 0)) throw std::invalid_argument("idealChainRelMse: the target is zero everywhere");
  std::vector<double> terms(c.size(), 0.0);
  for (size_t j = 0; j < c.size(); ++j) {
    const double a = pixelWeight(reference[j], eps);
    if (a == 0) continue;
    terms[j] = c[j] == 0 ? std::numeric_limits<double>::infinity() : a * C / (mutations * c[j]);
  }
  return terms;
}

double idealChainRelMse(const std::vector<Color>& reference, const std::vector<double>& c, double mutations,
                        double eps) {
  double sum = 0;
  for (double t : idealChainTerms(reference, c, mutations, eps)) sum += t;  // +inf stays +inf
  return sum / double(reference.size());
}

IdealChainBounds idealChainBounds(const std::vector<Color>& reference, double mutations, double eps) {
  std::vector<double> uniform(reference.size(), 1.0), best(reference.size());
  for (size_t j = 0; j < reference.size(); ++j) best[j] = std::sqrt(pixelWeight(reference[j], eps));
  IdealChainBounds r;
  r.luminance = idealChainRelMse(reference, luminanceTarget(reference), mutations, eps);
  r.uniform = idealChainRelMse(reference, uniform, mutations, eps);
  r.best = idealChainRelMse(reference, best, mutations, eps);
  return r;
}

std::vector<double> idealLuminanceChainTerms(const std::vector<Color>& reference, double mutations, double eps) {
  if (!(mutations > 0) || reference.empty()) return {};
  const std::vector<double> lum = luminanceTarget(reference);
  double total = 0;
  for (double l : lum) total += l;
  if (!(total > 0) || !std::isfinite(total)) return {};
  std::vector<double> terms = idealChainTerms(reference, lum, mutations, eps);
  for (double t : terms)
    if (!std::isfinite(t)) return {};
  return terms;
}

double idealLuminanceChainRelMse(const std::vector<Color>& reference, double mutations, double eps) {
  const std::vector<double> terms = idealLuminanceChainTerms(reference, mutations, eps);
  if (terms.empty()) return -1;
  double sum = 0;
  for (double t : terms) sum += t;
  return sum / double(reference.size());
}

}  // namespace mlt::eval
