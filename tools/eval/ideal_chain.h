// What a Markov chain could reach at best on an image: the relMSE of an *ideal* chain, one whose N
// mutations are independent draws from its target (perfect mixing, no start-up), against the image itself.
//
// A chain with target c visits pixel j a number of times n_j ~ Poisson(N c_j / C), C = sum_j c_j (c_j the
// target's integral over the pixel), and every visit carries f / c (develop.h (D1)). With c proportional to
// the pixel's luminance within it (f / c constant over the pixel: the chain's best case), the estimate is
// I^_jc = I_jc n_j / E[n_j], whose variance is I_jc^2 / E[n_j]. So, with eps the harness's relMSE epsilon,
//     relMSE(c) = (1 / P) sum_j a_j C / (N c_j),      a_j = (1/3) sum_c I_jc^2 / (I_jc^2 + eps)      (I1)
// for
//   - luminance, c_j = L_j (Veach's and Kelemen's target, mmlt's default);
//   - uniform,   c_j = 1 (every pixel visited alike): relMSE = sum_j a_j / N;
//   - best,      c_j = sqrt(a_j), the minimum of (I1) over every c by Cauchy-Schwarz:
//                relMSE = (sum_j sqrt(a_j))^2 / (P N)  (the allocation n_j ~ I_j / sqrt(I_j^2 + eps) of
//                common/mlt/importance.h (R1)).
// A real chain is correlated (its visits are not independent), so its relMSE at N mutations is above
// these; their ratio is how much of its N the correlation costs. They are not bounds for a job that
// renders part of the light by another estimator (a pt pass, or Kelemen MIS large steps, whose samples
// have less variance per visit than one Poisson count where the light is smooth).
#pragma once
#include <vector>

#include "common/core/color.h"

namespace mlt::eval {

// (I1) for a target given per pixel (c.size() == reference.size(), c_j >= 0, some c_j > 0; mutations > 0;
// std::invalid_argument otherwise). A pixel with a_j > 0 that the target never visits (c_j = 0) makes the
// result +infinity; black pixels (a_j = 0) cost nothing.
double idealChainRelMse(const std::vector<Color>& reference, const std::vector<double>& c, double mutations,
                        double eps = 1e-2);
// The terms of (I1) per pixel, a_j C / (N c_j) (0 for a black pixel, +infinity for a lit pixel the target
// never visits): idealChainRelMse is their mean. Same checks as idealChainRelMse.
std::vector<double> idealChainTerms(const std::vector<Color>& reference, const std::vector<double>& c,
                                    double mutations, double eps = 1e-2);

struct IdealChainBounds {
  double luminance = 0;  // c = the pixel's luminance
  double uniform = 0;    // c = 1
  double best = 0;       // c = sqrt(a_j): the smallest (I1) of any target
};
IdealChainBounds idealChainBounds(const std::vector<Color>& reference, double mutations, double eps = 1e-2);

// The harness's figure per chain run: bounds.luminance, or -1 where it is not a number to compare with (no
// mutations, a reference without light, a lit pixel of zero luminance).
double idealLuminanceChainRelMse(const std::vector<Color>& reference, double mutations, double eps = 1e-2);
// Its per-pixel terms (idealChainTerms of the luminance target); empty where it is -1.
std::vector<double> idealLuminanceChainTerms(const std::vector<Color>& reference, double mutations,
                                             double eps = 1e-2);

}  // namespace mlt::eval
