#include "common/methods/mmlt/mmlt_method.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "common/mlt/target.h"
#include "common/render/render_scene.h"

namespace mlt {

int mmltTechniqueCount(int k) { return k <= 1 ? 1 : k + 1; }

double mmltBSample(const RenderScene& scene, SampleSource& source, int k, MisHeuristic heuristic, BdptWorkspace& ws) {
  if (k < 1) throw std::invalid_argument("mmlt: path length " + std::to_string(k) + " must be >= 1");
  return targetFunction(evaluateLength(scene, source, k, heuristic, ws));
}

MmltTarget::MmltTarget(const RenderScene& scene, const IntegratorSettings& integrator)
    : scene_(scene), integrator_(integrator) {
  const int k = integrator.maxDepth < 0 ? kUnlimitedVertices : integrator.maxDepth;
  ws_.reserve(k + 2, k + 1);
}

void MmltTarget::evaluate(SampleSource& source, int pathLength, PathContribution& out) {
  out.clear();
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

ParamSpec mmltBSampleParam() {
  ParamSpec p;
  p.name = "b-sample-every";
  p.type = ParamSpec::Type::Int;
  p.defaultValue = kDefaultBSampleEvery;
  p.help = "mutations per b sample: each chain of length k also evaluates every technique of length k at a fresh "
           "uniform point this often, and b_k is refined by those samples (Rao-Blackwellized: a lighter tail than "
           "the large steps' one technique; develop.h (D9)); 0: by the large steps";
  p.min = 0;
  p.max = 1 << 20;
  return p;
}

uint64_t mmltMutationsPerBSample(const RenderMethod& method, const RenderSettings& settings, int k) {
  return mmltTechniqueCount(k) > 1 ? uint64_t(method.param(settings, "b-sample-every")) : 0;
}

std::vector<ParamSpec> MmltMethod::params() const {
  std::vector<ParamSpec> all = PrimarySampleChainMethod::params();
  all.push_back(mmltBSampleParam());
  return all;
}

std::unique_ptr<PssTarget> MmltMethod::makeTarget(const RenderScene& scene, const RenderSettings& settings) const {
  // separateDirect needs nothing here: the chains' lengths start after the direct pass's (chainMinLength).
  return std::make_unique<MmltTarget>(scene, settings.integrator);
}

}  // namespace mlt
