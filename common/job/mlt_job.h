// The Markov-chain half of the job API (pssmlt, pssmlt-bdpt, mmlt). render_job.cpp dispatches to these
// for every method with isMarkovChainMethod(method) == true; the sample-based half (pt, lt, bdpt) lives
// in sample_job.h.
// Implemented in common/job/mlt_job.cpp (with common/mlt/).
#pragma once
#include <vector>

#include "common/job/render_job.h"
#include "common/mlt/bootstrap.h"

namespace mlt {

// The bootstrap of a Markov chain job: a pure function of the scene and of the settings it reads (seed,
// method, width/height, integrator, separateDirect, bootstrapSamples). mutationsPerPixel, chains, the
// mutation kernel and the large-step probability do not enter it, so one bootstrap serves plans with any
// number of mutations (a time-budgeted render plans twice from one bootstrap; see render_local.cpp).
struct MarkovChainBootstrap {
  RenderSettings settings;  // the settings it was computed with (width/height resolved)
  BootstrapResult result;
};

// settings.width/height must be resolved against the scene camera (planJob does this).
// Bootstrap sizing (common/mlt/bootstrap.h): RenderSettings::bootstrapSamples candidates per path length
// to start with; while b's relative standard error is above 1%, the length contributing most to it
// doubles its candidates, up to 8x.
constexpr double kBootstrapTargetRelStdErr = 0.01;
constexpr uint64_t kBootstrapMaxGrowth = 8;

// Throws std::invalid_argument naming the setting if a Markov chain job cannot be planned with these
// (resolved) settings, e.g. mmlt with unlimited depth. Cheap: the coordinator calls it at submission.
void validateMarkovChainSettings(const RenderSettings& settings);
MarkovChainBootstrap bootstrapMarkovChainJob(const RenderScene& scene, const RenderSettings& settings);
// Chain allocation from an existing bootstrap: the same plan, bit for bit, as planMarkovChainJob(scene,
// settings). Throws std::invalid_argument naming the field if `settings` differs from the bootstrap's in
// a field the bootstrap reads.
JobPlan planMarkovChainJob(const RenderScene& scene, const RenderSettings& settings, const MarkovChainBootstrap& boot);
// Bootstrap (b, bk, candidates), chain allocation: a plan whose units are chains. settings.width/height
// are already resolved against the scene camera by planJob.
JobPlan planMarkovChainJob(const RenderScene& scene, const RenderSettings& settings);
// Runs one chain (unit.startCandidate, unit.mutations, ...) and returns its raw splat sums + stats.
PartialResult runMarkovChain(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit);
// Normalization of the merged chains (b * P / M per length; see mlt/develop.h).
std::vector<Color> developMarkovChainImage(const JobPlan& plan, const PartialResult& merged);

}  // namespace mlt
