// Error metrics of a rendered image against a reference, and the reference's own noise level.
//
// All averages run over pixels and the three channels (x = rendered, r = reference, per channel):
//   relMSE  = mean (x - r)^2 / (r^2 + eps)        relative MSE; eps keeps black pixels from dominating
//   MSE     = mean (x - r)^2
//   MAE     = mean |x - r|
//   meanErr = (mean x - mean r) / mean r          signed relative error of the mean brightness
//   topShare = share of the relMSE sum held by the kTopPixels worst pixels (0 for an exact image): a run
//              whose error sits in a few pixels (a Markov chain confined to them, one firefly) reads near 1
// Non-finite rendered values are excluded from every average and counted (ImageMetrics::nonFinite).
//
// Reference noise. A reference is the average of K independent parts (different seeds). With s^2 the
// per-pixel sample variance of the parts, the reference's variance is s^2 / K, and a perfect render
// measured against it would still show
//   relMSE floor = mean (s^2 / K) / (r^2 + eps),      MSE floor = mean s^2 / K,
// since E[(x - r_hat)^2] = E[(x - r)^2] + Var(r_hat) for x independent of r_hat. The mean brightness
// of the reference carries a relative standard error std(m_k) / sqrt(K) / mean r over the part means
// m_k. Reports use these numbers so that no comparison claims more accuracy than the reference has.
#pragma once
#include <cstdint>
#include <vector>

#include "common/core/color.h"

namespace mlt::eval {

constexpr int kTopPixels = 4;

struct ImageMetrics {
  double relMSE = 0, mse = 0, mae = 0;
  double topShare = 0;    // of relMSE, in the kTopPixels worst pixels
  uint64_t pixels = 0;    // of the image
  uint64_t worstPixel = 0;  // index (y * width + x) of the pixel with the largest relative error
  double meanErr = 0;     // relative, signed
  double mean = 0;        // mean of the rendered image (over pixels and channels)
  double refMean = 0;
  uint64_t nonFinite = 0; // non-finite channel values excluded
};

// Sizes must match and be non-empty (std::invalid_argument otherwise).
ImageMetrics computeMetrics(const std::vector<Color>& image, const std::vector<Color>& reference,
                            double eps = 1e-2);

// Per-pixel relative squared error averaged over channels: (x - r)^2 / (r^2 + eps). Non-finite -> +inf.
std::vector<float> relativeErrorMap(const std::vector<Color>& image, const std::vector<Color>& reference,
                                    double eps = 1e-2);

struct ReferenceNoise {
  int parts = 0;               // K; 0 = unknown (user-supplied reference)
  double relMSEFloor = 0;      // expected relMSE of a perfect image against this reference
  double mseFloor = 0;
  double meanRelStdErr = 0;    // relative standard error of the reference's mean brightness
};

struct ReferenceEstimate {
  std::vector<Color> mean;      // the reference image: average of the parts
  std::vector<Color> variance;  // per-pixel variance of the mean (s^2 / K)
  ReferenceNoise noise;
};

// Needs K >= 2 parts of equal size (std::invalid_argument otherwise).
ReferenceEstimate estimateReference(const std::vector<std::vector<Color>>& parts, double eps = 1e-2);
// Floors for a reference whose per-pixel variance image is known (e.g. read back from the cache).
ReferenceNoise noiseFromVariance(const std::vector<Color>& reference, const std::vector<Color>& variance,
                                 int parts, double meanRelStdErr, double eps = 1e-2);

}  // namespace mlt::eval
