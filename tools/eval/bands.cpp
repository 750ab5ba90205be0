#include "tools/eval/bands.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "tools/eval/ideal_chain.h"

namespace mlt::eval {

namespace {
// bands[j], checked to name a band (std::invalid_argument naming the caller and the pixel otherwise).
size_t bandAt(const std::vector<int>& bands, size_t j, const char* who) {
  const int b = bands[j];
  if (b < 0 || b >= kBands)
    throw std::invalid_argument(std::string(who) + ": band " + std::to_string(b) + " at pixel " + std::to_string(j));
  return size_t(b);
}
}  // namespace

std::string bandName(int band) {
  switch (band) {
    case 0: return "darkest 50%";
    case 1: return "50-90%";
    case 2: return "90-99%";
    case 3: return "brightest 1%";
  }
  throw std::invalid_argument("bandName: no band " + std::to_string(band));
}

std::vector<int> brightnessBands(const std::vector<Color>& reference) {
  if (reference.empty()) throw std::invalid_argument("brightnessBands: empty reference");
  const size_t P = reference.size();
  std::vector<double> lum(P);
  for (size_t j = 0; j < P; ++j) lum[j] = double(luminance(reference[j]));
  std::vector<size_t> order(P);
  std::iota(order.begin(), order.end(), size_t(0));
  // Ascending luminance, ties by index (a deterministic order; NaN, which no reference holds, sorts first).
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const bool na = std::isnan(lum[a]), nb = std::isnan(lum[b]);
    if (na != nb) return na;
    return !na && lum[a] < lum[b];
  });
  std::vector<int> band(P, 0);
  size_t begin = 0;
  for (int b = 0; b < kBands; ++b) {
    const size_t end = b + 1 == kBands ? P : size_t(std::floor(kBandUpper[size_t(b)] * double(P)));
    for (size_t r = begin; r < end; ++r) band[order[r]] = b;
    begin = std::max(begin, end);
  }
  return band;
}

BandValues bandRelMse(const std::vector<Color>& image, const std::vector<Color>& reference,
                      const std::vector<int>& bands, double eps) {
  if (image.size() != reference.size() || bands.size() != reference.size())
    throw std::invalid_argument("bandRelMse: " + std::to_string(image.size()) + " image pixels, " +
                                std::to_string(reference.size()) + " reference pixels, " +
                                std::to_string(bands.size()) + " band entries (must be equal)");
  BandValues sum{};
  uint64_t n = 0;  // finite channel values: the denominator of computeMetrics' relMSE
  for (size_t j = 0; j < image.size(); ++j) {
    const size_t b = bandAt(bands, j, "bandRelMse");
    for (int c = 0; c < 3; ++c) {
      const double x = image[j][c], r = reference[j][c];
      if (!std::isfinite(x)) continue;
      sum[b] += (x - r) * (x - r) / (r * r + eps);
      ++n;
    }
  }
  for (double& s : sum) s = n > 0 ? s / double(n) : std::numeric_limits<double>::infinity();
  return sum;
}

BandValues idealLuminanceChainBands(const std::vector<Color>& reference, const std::vector<int>& bands,
                                    double mutations, double eps) {
  if (bands.size() != reference.size())
    throw std::invalid_argument("idealLuminanceChainBands: " + std::to_string(bands.size()) + " band entries for " +
                                std::to_string(reference.size()) + " pixels");
  const std::vector<double> terms = idealLuminanceChainTerms(reference, mutations, eps);
  if (terms.empty()) return kUnknownBands;
  BandValues out{};
  for (size_t j = 0; j < terms.size(); ++j) out[bandAt(bands, j, "idealLuminanceChainBands")] += terms[j];
  for (double& v : out) v /= double(reference.size());
  return out;
}

}  // namespace mlt::eval
