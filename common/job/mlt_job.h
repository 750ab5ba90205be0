// The Markov-chain half of the job API (pssmlt, pssmlt-bdpt, mmlt). render_job.cpp dispatches to these
// for every method with isMarkovChainMethod(method) == true; the sample-based half (pt, lt, bdpt) lives
// in sample_job.h.
// Implemented in common/job/mlt_job.cpp (with common/mlt/).
#pragma once
#include <vector>

#include "common/job/render_job.h"

namespace mlt {

// Bootstrap (b, bk, candidates), chain allocation: a plan whose units are chains. settings.width/height
// are already resolved against the scene camera by planJob.
JobPlan planMarkovChainJob(const RenderScene& scene, const RenderSettings& settings);
// Runs one chain (unit.startCandidate, unit.mutations, ...) and returns its raw splat sums + stats.
PartialResult runMarkovChain(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit);
// Normalization of the merged chains (b * P / M per length; see mlt/develop.h).
std::vector<Color> developMarkovChainImage(const JobPlan& plan, const PartialResult& merged);

}  // namespace mlt
