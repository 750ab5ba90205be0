// A relative target: the chains' target c weighted by an importance map over the film, so that they spend
// their mutations where the image's *relative* error is made, not where it is bright.
//
// The estimator (develop.h (D1)) is unbiased for any target c > 0 wherever f != 0: a chain visits u with
// density c(u) / b and every visit carries f / c. With c = luminance(f) (Veach's and Kelemen's choice) the
// mutations a pixel gets are in proportion to its brightness I_j, and the relative variance of pixel j
// goes as 1 / I_j: a bright highlight is over-sampled and the dark plate next to it is noisy. The error
// people judge, and the results page measures, is relative: relMSE = mean_j (I^_j - I_j)^2 / (I_j^2 + eps).
// If pixel j gets n_j mutations and its variance is ~ I_j^2 / n_j (a chain's relative error per visit,
// alike over the image), minimizing sum_j I_j^2 / (n_j (I_j^2 + eps)) under sum_j n_j = M gives
//     n_j  ~  I_j / sqrt(I_j^2 + eps)                                  (Lagrange multipliers)     (R1)
// and a target that visits pixel j that often is
//     c(u) = sum over the path's splats i of  luminance(f_i) h(pixel of splat i),
//     h_j  = 1 / sqrt(g_j^2 + (kappa gbar)^2),                                                     (R2)
// with g_j an estimate of pixel j's luminance I_j (the importance pilot, common/job/importance_pilot.h),
// gbar its mean over the film and kappa the floor (the methods' parameter target-floor,
// ChainJobSpec::importanceFloor): pixels much brighter than
// kappa gbar get mutations in proportion to I_j / g_j ~ 1 (flat), darker ones in proportion to their
// brightness, as luminance would (an image's black regions are not worth a chain's time). This is
// Hoberock and Hart's "arbitrary importance functions for MLT" (2010) with the importance chosen for relMSE.
// b = E[c] then integrates h-weighted luminance; the bootstrap, the large steps, the tail split and the
// development are unchanged, (D1)-(D7) hold for any c, and (D8) takes each length's brightness from
// luminance. A wrong g costs variance, never bias, because h is fixed before any sample of b or of the
// chains is drawn; but the variance can be large: light the pilot missed (a caustic seen in a mirror)
// sits in tiles with the largest h, where its rare paths become peaks of the target that hold a chain
// (docs/CHAINS.md, "A relative target again": why it is not the default).
//
// The map is per tile of T x T pixels (at most kImportanceMaxTiles per axis, so that a plan carries at most
// 64 x 64 floats whatever the film) and read by the splat's raster position.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "common/core/vec.h"

namespace mlt {

constexpr int kImportanceMaxTiles = 64;

struct ImportanceMap {
  int filmWidth = 0, filmHeight = 0;
  int tileSize = 0;          // T: pixels per tile side
  int tilesX = 0, tilesY = 0;
  std::vector<float> h;      // per tile, row-major from the top-left; empty: no map (c = luminance)
  bool empty() const { return h.empty(); }
  // h of the tile holding raster position p (clamped to the film).
  float at(Vec2 p) const {
    const int x = std::clamp(int(p.x), 0, filmWidth - 1) / tileSize;
    const int y = std::clamp(int(p.y), 0, filmHeight - 1) / tileSize;
    return h[size_t(y) * size_t(tilesX) + size_t(x)];
  }
  bool operator==(const ImportanceMap&) const = default;
};

// T for a film: the smallest tile size giving at most kImportanceMaxTiles tiles per axis.
int importanceTileSize(int width, int height);
// A film's tile grid: film size, T and tilesX x tilesY filled in, h empty (throws on an empty film).
ImportanceMap importanceGrid(int filmWidth, int filmHeight);

// (R2) from per-tile sums of the pilot's luminance samples and their counts (tilesX x tilesY, as
// importanceTileSize makes them): g of a tile is the mean over it and its 8 neighbours (a 3 x 3 box of
// tiles, clipped to the film), gbar the mean over all samples, h = 1 / sqrt(g^2 + (floor gbar)^2),
// scaled so that the mean of h g over the samples is gbar (c keeps luminance's scale). A pilot that saw no
// light (gbar = 0) gives an empty map: luminance.
ImportanceMap importanceFromTileSums(int filmWidth, int filmHeight, const std::vector<double>& tileSums,
                                     const std::vector<uint64_t>& tileCounts, double floor);

// Throws std::invalid_argument naming `field` unless the map is empty or consistent: film and tile sizes
// positive, tilesX/Y those of importanceTileSize, h of tilesX x tilesY finite positive values.
void validateImportanceMap(const ImportanceMap& map, const char* field);

}  // namespace mlt
