#include "common/mlt/method_target.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/mlt/develop.h"
#include "common/render/render_scene.h"

#if __has_include("common/integrators/evaluators.h")
#include "common/integrators/evaluators.h"
#define MLT_MT_HAVE_EVALUATORS 1
#else
#define MLT_MT_HAVE_EVALUATORS 0
#endif

namespace mlt {

int mmltTechniqueCount(int k) { return k <= 1 ? 1 : k + 1; }
int mmltMinLength(bool separateDirect) { return separateDirect ? kDirectMaxSegments + 1 : 1; }

MethodTarget::MethodTarget(const RenderScene& scene, Method method, const IntegratorSettings& integrator,
                           bool separateDirect)
    : scene_(scene), method_(method), integrator_(integrator), separateDirect_(separateDirect) {
  if (method == Method::PSSMLT || method == Method::PSSMLT_BDPT) {
#if MLT_MT_HAVE_EVALUATORS
    evaluator_ = makeEvaluator(scene, method == Method::PSSMLT ? Method::PT : Method::BDPT, integrator);
#else
    throw std::runtime_error(std::string("method '") + methodName(method) + "': path evaluators are not built yet");
#endif
  } else if (method == Method::MMLT) {
    const int k = integrator.maxDepth < 0 ? kUnlimitedVertices : integrator.maxDepth;
    ws_.reserve(k + 2, k + 1);
  } else {
    throw std::invalid_argument(std::string("MethodTarget: '") + methodName(method) + "' is not a Markov chain method");
  }
}

MethodTarget::~MethodTarget() = default;

void MethodTarget::evaluate(SampleSource& source, int pathLength, PathContribution& out) {
  out.clear();
  if (method_ != Method::MMLT) {
    evaluator_->evaluate(source, nullptr, out);
    if (separateDirect_) {
      // Path of s + t vertices has s + t - 1 segments. Splats without (s, t) cannot be classified.
      for (const Splat& sp : out.splats)
        if (sp.s < 0 || sp.t < 0)
          throw std::logic_error("separateDirect: the path evaluator does not label its splats with (s, t)");
      std::erase_if(out.splats, [](const Splat& sp) { return sp.s + sp.t - 1 <= kDirectMaxSegments; });
    }
    return;
  }
  const int k = pathLength;
  if (k < 1) throw std::invalid_argument("mmlt: path length " + std::to_string(k) + " must be >= 1");
  const int n = mmltTechniqueCount(k);
  source.startStream(Stream::Connect);
  source.seek(kConnectTechniqueDim);
  const int s = k <= 1 ? 0 : std::min(n - 1, static_cast<int>(source.next1D() * float(n)));
  const int t = k + 1 - s;
  const TechniqueSample ts = evaluateTechnique(scene_, source, s, t, integrator_.heuristic, ws_);
  const float w = ts.weight * float(n);
  if (w > 0 && !ts.C.isBlack()) {
    Splat sp;
    sp.pRaster = ts.pRaster;
    sp.L = ts.C * w;
    sp.s = static_cast<int16_t>(s);
    sp.t = static_cast<int16_t>(t);
    out.splats.push_back(sp);
  }
}

}  // namespace mlt
