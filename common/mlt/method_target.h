// The function each Markov chain method samples, as a map (sample source, path length) -> path
// contribution. The bootstrap and the chains call the same object, so a chain's replay of its start
// candidate reproduces the bootstrap's value bit for bit.
//   pssmlt       the path tracer evaluator (film position from the camera stream)
//   pssmlt-bdpt  the bdpt evaluator: all strategies of one sample, each splat MIS-weighted
//   mmlt         one bdpt technique (s, t) for path length k (segments) (Hachisuka et al. 2014): Connect
//                [kConnectTechniqueDim] picks s uniformly among the nTechniques(k) strategies, t = k + 1 - s;
//                contribution = C(s,t) * w(s,t) * nTechniques(k), so that summing over the uniform
//                technique choice gives sum_(s,t) w C = the bdpt estimate of length k.
// separateDirect: paths of at most kDirectMaxSegments segments are dropped (rendered by bdpt instead).
#pragma once
#include <memory>

#include "common/integrators/bdpt.h"
#include "common/integrators/path_evaluator.h"
#include "common/job/render_job.h"
#include "common/mlt/chain.h"

namespace mlt {

class RenderScene;

// Strategies bdpt weights for a path of k segments: (s, t) with s + t = k + 1, t >= 1, without (1, 1)
// (see bdpt.h). k = 1: only (0, 2); k >= 2: s = 0..k.
int mmltTechniqueCount(int k);
// Path length range a method's chains cover, given max depth and separateDirect: [kMin, kMax].
int mmltMinLength(bool separateDirect);

class MethodTarget {
 public:
  MethodTarget(const RenderScene& scene, Method method, const IntegratorSettings& integrator, bool separateDirect);
  ~MethodTarget();
  // pathLength: mmlt's k; ignored (-1) for pssmlt methods.
  void evaluate(SampleSource& source, int pathLength, PathContribution& out);

 private:
  const RenderScene& scene_;
  Method method_;
  IntegratorSettings integrator_;
  bool separateDirect_;
  std::unique_ptr<PathEvaluator> evaluator_;
  BdptWorkspace ws_;
};

// ChainTarget adapter: evaluates a MethodTarget on a fixed source and length.
class MethodChainTarget final : public ChainTarget {
 public:
  MethodChainTarget(MethodTarget& target, SampleSource& source, int pathLength)
      : target_(target), source_(source), pathLength_(pathLength) {}
  void evaluate(PathContribution& out) override { target_.evaluate(source_, pathLength_, out); }

 private:
  MethodTarget& target_;
  SampleSource& source_;
  int pathLength_;
};

}  // namespace mlt
