// b's large steps post-stratified by film position (develop.h (D6)).
//
// Every large step of a primary-sample chain is a uniform sample u of U; its camera coordinates
// Camera[0,1] are uniform on [0,1)^2 and pick a pixel j with probability 1 / P. The chain keeps, per pixel,
// the count n_j of its large steps there, the sum of their bulk m = min(c, tau) and the sum of m^2: a film
// layer of (n, sum m, sum m^2) per path length slot (bStrataLayer), merged by addition like any splat
// layer. Since b's bulk is the mean over pixels of E[m | j], the post-stratified estimate
//     m^ = sum_r (A_r / P) * mean of m over the samples in stratum r,
//     Var(m^) = sum_r (A_r / P)^2 * s_r^2 / n_r                                               (D6)
// (A_r the pixels of stratum r, s_r^2 its samples' variance) drops the variance between strata: where the
// light or a bright wall is seen directly, c depends mostly on the pixel (bdpt on the Cornell box, 256x256:
// per-sample variance 80x the variance within a pixel; caustic-mirror: 1.02x, nothing to gain).
//
// Strata are the nodes of a quadtree over the film (a power-of-two square covering it; nodes outside the
// film are dropped, edge nodes have A_r < their square): a node is split into its children when every
// child that covers pixels has at least 2 samples (so that s_r^2 exists), else its samples are pooled.
// The choice depends on the counts only, which do not depend on c, and is symmetric in a node's children,
// so for children of equal area E[n_child / n_node | the choice] = 1/4 and the pooled mean stays unbiased;
// the root pooled is the plain mean of every large step.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/film/film.h"
#include "common/mlt/target_sums.h"  // StratifiedMean

namespace mlt {

// The film layer value one large step adds at its pixel: (1, m, m^2).
inline RGBd strataSample(double m) { return RGBd{1.0, m, m * m}; }
// The pixel of a stratum point u in [0,1)^2 on a width x height film.
size_t strataPixel(float ux, float uy, int width, int height);

// (D6) over a layer of (n, sum m, sum m^2) per pixel (row-major, width x height).
StratifiedMean postStratifiedMean(std::span<const RGBd> layer, int width, int height);

}  // namespace mlt
