// The Markov-chain half of the job API (pssmlt, pssmlt-bdpt, mmlt). render_job.cpp dispatches to these
// for every method with isMarkovChainMethod(method) == true; the sample-based half (pt, lt, bdpt) lives
// in sample_job.h.
//
// NOTE for the mlt helper (owner of the implementation, common/job/mlt_job.cpp + common/mlt/): the
// film helper wrote these three declarations so the job API links before the chains exist. A temporary
// stub, common/job/mlt_job_stub.cpp, defines them as *weak* symbols that throw "not implemented yet";
// your strong definitions in mlt_job.cpp win at link time. Delete mlt_job_stub.cpp when you commit
// mlt_job.cpp (the film helper will also delete it once mlt_job.cpp is in the tree).
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
