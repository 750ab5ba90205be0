// Unidirectional path tracing with next-event estimation and multiple importance sampling between BSDF
// sampling and light sampling (Veach 1997, sec. 9.2; the light chosen in proportion to power).
//
// maxDepth counts path segments (maxDepth = 1: only emitters seen directly). Russian roulette once a
// path has rrDepth segments: survival probability min(1, max component of the throughput), read from
// entry [3] of the vertex's block. Output: one splat (t = -1) at the camera raster position, or none
// when the path carries no light.
//
// Streams read: Camera [0,1] raster, [2,3] lens; bounce i (i-th surface vertex) Camera block
// kCameraDims + i * kBsdfDims; its next-event estimation Connect block connectNeeOffset(i).
#pragma once
#include "common/integrators/path_evaluator.h"

namespace mlt {

class PathTracer final : public PathEvaluator {
 public:
  PathTracer(const RenderScene& scene, const IntegratorSettings& settings) : scene_(scene), settings_(settings) {}
  void evaluate(SampleSource& source, const Vec2* pixel, PathContribution& out) const override;
  // The radiance estimate alone (cameraRaster is written to *pRaster).
  Color Li(SampleSource& source, const Vec2* pixel, Vec2* pRaster) const;

 private:
  const RenderScene& scene_;
  IntegratorSettings settings_;
};

}  // namespace mlt
