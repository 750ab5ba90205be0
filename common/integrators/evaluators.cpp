// bdpt and lt evaluators over the free functions of bdpt.h, and the factory.
#include "common/integrators/evaluators.h"

#include <stdexcept>
#include <string>

#include "common/integrators/bdpt.h"
#include "common/integrators/path_tracer.h"
#include "common/render/render_scene.h"

namespace mlt {

namespace {

// One workspace per thread: vertex arrays grow once and are reused by every sample.
BdptWorkspace& threadWorkspace() {
  thread_local BdptWorkspace ws;
  return ws;
}

}  // namespace

void BdptEvaluator::evaluate(SampleSource& source, const Vec2* pixel, PathContribution& out) const {
  out.clear();
  const int maxDepth = settings_.maxDepth;
  BdptWorkspace& ws = threadWorkspace();
  const int maxCamera = maxCameraVertices(maxDepth), maxLight = maxLightVertices(maxDepth);
  ws.reserve(maxCamera, std::max(maxLight, 1));
  Vertex* camera = ws.camera.data();
  Vertex* light = ws.light.data();
  const int nCamera = generateCameraSubpath(scene_, source, pixel, maxCamera, settings_.rrDepth, camera,
                                            &out.cameraRaster);
  const int nLight = generateLightSubpath(scene_, source, maxLight, settings_.rrDepth, light);
  for (int t = 1; t <= nCamera; ++t) {
    for (int s = 0; s <= nLight; ++s) {
      const int segments = s + t - 1;
      if ((s == 1 && t == 1) || segments < 1 || (maxDepth >= 0 && segments > maxDepth)) continue;
      if (s == 0 && dropLightViews_ && isLightView(camera, t)) continue;
      Vertex sampled;
      Vec2 pRaster = out.cameraRaster;
      const Color C = connectBdpt(scene_, source, light, s, camera, t, &sampled, &pRaster);
      if (C.isBlack()) continue;
      const float w = misWeight(scene_, light, s, camera, t, sampled, settings_.heuristic);
      const Color L = C * w;
      if (L.isBlack()) continue;
      out.splats.push_back(Splat{pRaster, L, int16_t(s), int16_t(t)});
    }
  }
}

void LightTracer::evaluate(SampleSource& source, const Vec2* pixel, PathContribution& out) const {
  (void)pixel;
  out.clear();
  BdptWorkspace& ws = threadWorkspace();
  const int maxLight = maxLightVertices(settings_.maxDepth);
  ws.reserve(1, std::max(maxLight, 1));
  Vertex* light = ws.light.data();
  const int nLight = generateLightSubpath(scene_, source, maxLight, settings_.rrDepth, light);
  for (int s = 1; s <= nLight; ++s) {
    Vertex sampled;
    Vec2 pRaster;
    const Color C = connectBdpt(scene_, source, light, s, ws.camera.data(), 1, &sampled, &pRaster);
    if (!C.isBlack()) out.splats.push_back(Splat{pRaster, C, int16_t(s), 1});
  }
}

std::unique_ptr<PathEvaluator> makeEvaluator(const RenderScene& scene, const std::string& name,
                                             const IntegratorSettings& settings) {
  if (settings.maxDepth < -1)
    throw std::invalid_argument("integrator: maxDepth must be >= -1 (-1 = unlimited), got " +
                                std::to_string(settings.maxDepth));
  if (name == "pt") return std::make_unique<PathTracer>(scene, settings);
  if (name == "lt") return std::make_unique<LightTracer>(scene, settings);
  if (name == "bdpt") return std::make_unique<BdptEvaluator>(scene, settings);
  throw std::invalid_argument("makeEvaluator: '" + name + "' is not a path evaluator (pt, lt, bdpt)");
}

}  // namespace mlt
