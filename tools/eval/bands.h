// Where a run's error is: its relMSE split by the reference's brightness, and the same split of an ideal
// chain's (tools/eval/ideal_chain.h (I1)).
//
// The pixels are ranked by the reference's luminance (ties by pixel index) and cut at fixed quantiles into
// kBands bands: the darkest 50%, 50-90%, 90-99% and the brightest 1%. A band's figure is the relMSE sum over
// its pixels divided by the image's pixel count P, so the bands of a run add up to its relMSE:
//     relMSE_B = (1 / P) sum_{j in B} (1/3) sum_c (x_jc - r_jc)^2 / (r_jc^2 + eps)                     (B1)
// and the ideal chain's band is its (I1) sum restricted to B, (1 / P) sum_{j in B} a_j C / (N c_j), with
// the luminance target c_j = L_j and C over the whole image. A method's band over the ideal's band says
// where its chains' correlation (or a sampler's variance) costs the most: a chain that is 5x its ideal in
// the brightest 1% and 2x elsewhere loses in the highlights, one that is 10x everywhere mixes slowly alike.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "common/core/color.h"

namespace mlt::eval {

constexpr int kBands = 4;
// Upper quantile of each band's reference luminance (the last is 1).
constexpr std::array<double, kBands> kBandUpper = {0.5, 0.9, 0.99, 1.0};
// "darkest 50%", "50-90%", "90-99%", "brightest 1%".
std::string bandName(int band);

using BandValues = std::array<double, kBands>;
// Every band unknown (-1): a run without an ideal chain's figure.
inline constexpr BandValues kUnknownBands = [] {
  BandValues v{};
  v.fill(-1.0);
  return v;
}();

// The band (0 .. kBands-1) of every pixel of `reference` (empty reference: std::invalid_argument).
// Band b holds the pixels of rank [floor(q_{b-1} P), floor(q_b P)) in ascending luminance.
std::vector<int> brightnessBands(const std::vector<Color>& reference);

// (B1) per band; sizes must match (std::invalid_argument otherwise). Non-finite rendered values count as
// computeMetrics counts them: excluded (their pixel's channel adds nothing).
BandValues bandRelMse(const std::vector<Color>& image, const std::vector<Color>& reference,
                      const std::vector<int>& bands, double eps = 1e-2);

// The luminance-target ideal chain's (I1) per band at `mutations`; every entry -1 where
// idealLuminanceChainRelMse is -1 (nothing to compare with).
BandValues idealLuminanceChainBands(const std::vector<Color>& reference, const std::vector<int>& bands,
                                    double mutations, double eps = 1e-2);

}  // namespace mlt::eval
