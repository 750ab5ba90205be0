// The Markov chains' scalar target function c(x): the luminance of the path's total contribution (the
// sum of all of its splats, MIS-weighted; for mmlt the technique's weighted contribution). One function,
// used by the bootstrap (b = E[c]), by every chain's acceptance ratio and by the start-state replay check.
#pragma once
#include <cmath>

#include "common/core/color.h"
#include "common/integrators/path_evaluator.h"

namespace mlt {

// Non-finite or negative values are not a valid target: they count as 0 (the state is never accepted).
inline double targetFunction(const Color& total) {
  const double c = luminance(total);
  return std::isfinite(c) && c > 0 ? c : 0.0;
}
inline double targetFunction(const PathContribution& path) { return targetFunction(path.total()); }

}  // namespace mlt
