#include "tools/eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include "tools/eval/stats.h"

namespace mlt::eval {

namespace {
void checkSizes(size_t a, size_t b, const char* what) {
  if (a == 0 || a != b)
    throw std::invalid_argument(std::string(what) + ": image sizes differ or are empty (" + std::to_string(a) +
                                " vs " + std::to_string(b) + " pixels)");
}
double imageMean(const std::vector<Color>& img) {
  double s = 0;
  for (const Color& c : img) s += double(c.r) + double(c.g) + double(c.b);
  return s / (3.0 * double(img.size()));
}
}  // namespace

ImageMetrics computeMetrics(const std::vector<Color>& image, const std::vector<Color>& reference, double eps) {
  checkSizes(image.size(), reference.size(), "computeMetrics");
  ImageMetrics m;
  double sumRel = 0, sumSq = 0, sumAbs = 0, sumX = 0, sumR = 0;
  uint64_t n = 0;
  std::vector<double> pixelRel(image.size(), 0.0);  // per pixel, summed over its finite channels
  for (size_t i = 0; i < image.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      double r = reference[i][c];
      sumR += r;
      double x = image[i][c];
      if (!std::isfinite(x)) {
        ++m.nonFinite;
        continue;
      }
      double d = x - r;
      const double rel = d * d / (r * r + eps);
      sumRel += rel;
      pixelRel[i] += rel;
      sumSq += d * d;
      sumAbs += std::fabs(d);
      sumX += x;
      ++n;
    }
  }
  m.refMean = sumR / (3.0 * double(image.size()));
  if (n == 0) {
    double inf = std::numeric_limits<double>::infinity();
    m.relMSE = m.mse = m.mae = m.meanErr = inf;
    return m;
  }
  m.relMSE = sumRel / double(n);
  m.worstPixel = uint64_t(std::max_element(pixelRel.begin(), pixelRel.end()) - pixelRel.begin());
  const size_t top = std::min(pixelRel.size(), size_t(kTopPixels));
  std::partial_sort(pixelRel.begin(), pixelRel.begin() + std::ptrdiff_t(top), pixelRel.end(), std::greater<>());
  double sumTop = 0;
  for (size_t i = 0; i < top; ++i) sumTop += pixelRel[i];
  m.topShare = sumRel > 0 ? sumTop / sumRel : 0.0;
  m.pixels = image.size();
  m.mse = sumSq / double(n);
  m.mae = sumAbs / double(n);
  m.mean = sumX / double(n);
  m.meanErr = m.refMean != 0 ? (m.mean - m.refMean) / m.refMean : std::numeric_limits<double>::infinity();
  return m;
}

std::vector<float> relativeErrorMap(const std::vector<Color>& image, const std::vector<Color>& reference,
                                    double eps) {
  checkSizes(image.size(), reference.size(), "relativeErrorMap");
  std::vector<float> out(image.size());
  for (size_t i = 0; i < image.size(); ++i) {
    double s = 0;
    for (int c = 0; c < 3; ++c) {
      double r = reference[i][c], d = double(image[i][c]) - r;
      s += d * d / (r * r + eps);
    }
    out[i] = std::isfinite(s) ? float(s / 3) : std::numeric_limits<float>::infinity();
  }
  return out;
}

ReferenceNoise noiseFromVariance(const std::vector<Color>& reference, const std::vector<Color>& variance, int parts,
                                 double meanRelStdErr, double eps) {
  checkSizes(reference.size(), variance.size(), "noiseFromVariance");
  ReferenceNoise noise;
  noise.parts = parts;
  noise.meanRelStdErr = meanRelStdErr;
  double rel = 0, sq = 0;
  for (size_t i = 0; i < reference.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      double r = reference[i][c], v = variance[i][c];
      rel += v / (r * r + eps);
      sq += v;
    }
  double n = 3.0 * double(reference.size());
  noise.relMSEFloor = rel / n;
  noise.mseFloor = sq / n;
  return noise;
}

ReferenceEstimate estimateReference(const std::vector<std::vector<Color>>& parts, double eps) {
  if (parts.size() < 2) throw std::invalid_argument("estimateReference: needs at least 2 parts");
  const size_t P = parts[0].size();
  for (const auto& p : parts) checkSizes(P, p.size(), "estimateReference");
  const double K = double(parts.size());
  ReferenceEstimate est;
  est.mean.assign(P, Color());
  est.variance.assign(P, Color());
  for (size_t i = 0; i < P; ++i)
    for (int c = 0; c < 3; ++c) {
      double s = 0;
      for (const auto& p : parts) s += p[i][c];
      double m = s / K, s2 = 0;
      for (const auto& p : parts) s2 += (p[i][c] - m) * (p[i][c] - m);
      est.mean[i][c] = float(m);
      est.variance[i][c] = float(s2 / (K - 1) / K);  // variance of the mean of K parts
    }
  std::vector<double> partMeans;
  for (const auto& p : parts) partMeans.push_back(imageMean(p));
  double refMean = mean(partMeans);
  double relStdErr = refMean != 0 ? stddev(partMeans) / std::sqrt(K) / std::fabs(refMean) : 0;
  est.noise = noiseFromVariance(est.mean, est.variance, int(parts.size()), relStdErr, eps);
  return est;
}

}  // namespace mlt::eval
