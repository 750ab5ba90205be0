// The sample-based path evaluators: pt, lt and bdpt behind the PathEvaluator interface.
//
//  pt   - path tracing with NEE + MIS (path_tracer.h): one splat, t = -1, at the camera raster position.
//  lt   - light tracing: one light subpath, every vertex connected to the camera (bdpt's (s, 1)
//         strategies, unweighted, including (1, 1): area lights seen directly). Splats at their own raster
//         positions with t = 1; the pixel argument is ignored. Develop with splat scale P / N.
//  bdpt - one camera and one light subpath, every strategy (s, t) with 1 <= s + t - 1 <= maxDepth except
//         (1, 1), MIS-weighted (balance or power heuristic). Splats carry s and t, so a driver can keep
//         one image per technique; t >= 2 land on cameraRaster (a pixel estimate: sum them into one
//         camera sample), t = 1 splats land anywhere (splat buffer, scale P / N).
#pragma once
#include <memory>
#include <string>

#include "common/integrators/path_evaluator.h"

namespace mlt {

// The evaluators by name: "pt", "lt" or "bdpt" (the methods pt, lt and bdpt, and the evaluators the
// Markov chain methods wrap). Throws std::invalid_argument for another name or a max depth < -1.
std::unique_ptr<PathEvaluator> makeEvaluator(const RenderScene& scene, const std::string& name,
                                             const IntegratorSettings& settings);

class BdptEvaluator final : public PathEvaluator {
 public:
  // dropLightViews: leave out the paths E S* L (isLightView, bdpt.h; veach-mlt renders them apart).
  BdptEvaluator(const RenderScene& scene, const IntegratorSettings& settings, bool dropLightViews = false)
      : scene_(scene), settings_(settings), dropLightViews_(dropLightViews) {}
  void evaluate(SampleSource& source, const Vec2* pixel, PathContribution& out) const override;

 private:
  const RenderScene& scene_;
  IntegratorSettings settings_;
  bool dropLightViews_;
};

class LightTracer final : public PathEvaluator {
 public:
  LightTracer(const RenderScene& scene, const IntegratorSettings& settings) : scene_(scene), settings_(settings) {}
  void evaluate(SampleSource& source, const Vec2* pixel, PathContribution& out) const override;
  bool splatsOnly() const override { return true; }

 private:
  const RenderScene& scene_;
  IntegratorSettings settings_;
};

}  // namespace mlt
