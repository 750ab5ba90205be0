// The Markov chains' scalar target function c(x): the luminance of the path's total contribution (the
// sum of all of its splats, MIS-weighted; for mmlt the technique's weighted contribution), or with an
// importance map (importance.h (R2)) each splat's luminance weighted by its tile's h. One function, used by
// the bootstrap (b = E[c]), by every chain's acceptance ratio and by the start-state replay check.
#pragma once
#include <cmath>

#include "common/core/color.h"
#include "common/integrators/path_evaluator.h"
#include "common/mlt/importance.h"

namespace mlt {

// Non-finite or negative values are not a valid target: they count as 0 (the state is never accepted).
inline double targetFunction(const Color& total) {
  const double c = luminance(total);
  return std::isfinite(c) && c > 0 ? c : 0.0;
}
inline double targetFunction(const PathContribution& path) { return targetFunction(path.total()); }
// (R2): sum over splats of luminance(L_i) h(p_i); luminance of the total without a map (null or empty).
inline double targetFunction(const PathContribution& path, const ImportanceMap* importance) {
  if (!importance || importance->empty()) return targetFunction(path);
  double c = 0;
  for (const Splat& s : path.splats) c += luminance(s.L) * double(importance->at(s.pRaster));
  return std::isfinite(c) && c > 0 ? c : 0.0;
}

}  // namespace mlt
