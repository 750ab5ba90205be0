// A path evaluator is a deterministic function (scene, primary samples) -> splats. It never touches the
// film, a chain or statistics; pt, lt, bdpt and every Markov chain method call the same evaluators.
#pragma once
#include <cstdint>
#include <vector>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/sampler/sample_source.h"
#include "common/settings/render_settings.h"  // IntegratorSettings

namespace mlt {

class RenderScene;

struct Splat {
  Vec2 pRaster;        // film position in pixels
  Color L;             // contribution (already MIS-weighted and divided by its pdf)
  int16_t s = -1;      // light subpath vertices (bdpt technique); -1 when not applicable
  int16_t t = -1;      // camera subpath vertices; t == 1 means a splat away from the camera sample
};

struct PathContribution {
  Vec2 cameraRaster;          // raster position chosen by the camera stream (for t >= 2 splats)
  std::vector<Splat> splats;  // may be empty (no light carried)
  void clear() { splats.clear(); }
  Color total() const {
    Color c;
    for (const Splat& s : splats) c += s.L;
    return c;
  }
};

class PathEvaluator {
 public:
  virtual ~PathEvaluator() = default;
  // pixel: if set, the raster position is pixel + (first two camera numbers) (stratified local rendering);
  // otherwise the first two camera numbers span the whole film (Markov chains).
  virtual void evaluate(SampleSource& source, const Vec2* pixel, PathContribution& out) const = 0;
  // true: every splat lands anywhere on the film (a light tracer); false: splats with t >= 2 (or pt's
  // t < 0) are the camera sample's pixel estimate. Decides how a sample batch bins them (sample_job.h).
  virtual bool splatsOnly() const { return false; }
};

}  // namespace mlt
