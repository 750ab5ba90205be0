// The Markov chains' scalar target function c(x): the luminance of the path's total contribution (the
// sum of all of its splats, MIS-weighted; for mmlt the technique's weighted contribution), or with an
// importance map (importance.h (R2)) each splat's luminance weighted by its tile's h, and with a power
// beta < 1 that sum raised to beta (T1 below). One function, used by the bootstrap (b = E[c]), by every
// chain's acceptance ratio and by the start-state replay check.
//
// A tempered target (docs/CHAINS.md, "A tempered target"):
//     c(u) = ( sum over the path's splats i of luminance(f_i) h(pixel of splat i) )^beta,   0 < beta <= 1   (T1)
// The estimator (develop.h (D1)) is unbiased for any c > 0 wherever f != 0; beta < 1 flattens the target
// along every path as the map flattens it across pixels: a proposal r times darker than the current state
// is accepted with r^-beta instead of 1/r, so a chain leaves a bright isolated path sooner, and pixel j
// gets mutations in proportion to about I_j^beta, the darker ones more than with luminance. Each visit
// carries f / c = f / lum^beta, so the image's brightness comes from b_lum as with the map (develop.h (D8)).
#pragma once
#include <cmath>

#include "common/core/color.h"
#include "common/integrators/path_evaluator.h"
#include "common/mlt/importance.h"

namespace mlt {

// What c is made of besides the splats' luminance: the map's weights (R2) and the power (T1).
struct TargetShape {
  const ImportanceMap* importance = nullptr;  // null or empty: every h = 1
  double power = 1;                           // beta of (T1); 1: c is linear in f
  bool hasMap() const { return importance && !importance->empty(); }
  // Whether c differs from the path's luminance; then each slot's image is scaled to b_lum (develop.h (D8)).
  bool shaped() const { return hasMap() || power != 1; }
};

// Non-finite or negative values are not a valid target: they count as 0 (the state is never accepted).
inline double targetFunction(const Color& total) {
  const double c = luminance(total);
  return std::isfinite(c) && c > 0 ? c : 0.0;
}
inline double targetFunction(const PathContribution& path) { return targetFunction(path.total()); }
// (R2), (T1): sum over splats of luminance(L_i) h(p_i), to the power beta; luminance of the total without a
// map and with beta = 1.
inline double targetFunction(const PathContribution& path, const TargetShape& shape) {
  double c;
  if (shape.hasMap()) {
    c = 0;
    for (const Splat& s : path.splats) c += luminance(s.L) * double(shape.importance->at(s.pRaster));
  } else {
    c = luminance(path.total());
  }
  if (!(std::isfinite(c) && c > 0)) return 0.0;
  return shape.power == 1 ? c : std::pow(c, shape.power);
}

}  // namespace mlt
