// veach-mlt as a Markov chain job: the plan, one chain, the image. Same shapes as the other Markov chain
// methods (common/job/mlt_job.h), so partial films, merge and develop are the shared ones.
//
// Plan: the pssmlt-bdpt bootstrap and chain allocation, unchanged (VeachMltMethod is its ChainJobSpec, with
// pssmlt-bdpt's target), the settings' method set to "veach-mlt". Its candidates are bdpt samples u
// with c(u) = lum(sum of MIS-weighted strategies); b = E[c(u)] = integral of lum f(x) over path space,
// which is exactly the normalization of a path-space chain with target c(x) = lum f(x) (veach_chain.h).
// Chains start from the plan's resampled candidates (alias table, stratified), one strategy of the
// candidate chosen in proportion to its weighted contribution: starts distributed as c / b.
// Run: a chain replays its start candidate (the bootstrap's c must be reproduced), then runs
// unit.mutations steps of runChain with expected-value splatting into layer chainLayer(0); everything
// random is a pure function of (job seed, chain index): chainRng purposes 3 (start strategy) and 4
// (mutations), 1 (acceptance) as for every chain.
// Develop: (D1) of common/mlt/develop.h, b * P / M (the chains make no large steps, so b is the
// bootstrap's).
// Not supported yet: separateDirect (throws), Kelemen MIS splatting (ignored: expected values).
#pragma once
#include <string>
#include <vector>

#include "common/job/job_types.h"
#include "common/settings/render_settings.h"
#include "common/methods/veach/mutations.h"

namespace mlt {
class RenderScene;
}

namespace mlt::veach {

JobPlan planVeachJob(const RenderScene& scene, RenderSettings settings);
PartialResult runVeachChain(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit,
                            const MutationSettings& mutations);
std::vector<Color> developVeachImage(const JobPlan& plan, const PartialResult& merged);

// Per-mutation acceptance for logs and metadata: "bidir 0.412 (123/456), lens ..." over the merged stats.
std::string acceptanceSummary(const ChainStats& stats);

}  // namespace mlt::veach
