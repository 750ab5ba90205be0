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
// b: the bootstrap's, refined as the chains run by independent bootstrap candidates the chains evaluate
// beside their mutations (veachBSamples of them per chain; chainRng-independent stream of their own),
// kept in largeStepSums as the other methods keep their large steps' (develop.h (D3)-(D5)).
// Develop: (D1) of common/mlt/develop.h, b * P / M with that b.
// separateDirect (veach-mlt-lecture-cmu: "estimate direct illumination with standard methods ... and apply
// MLT only for indirect illumination"): paths
// of at most kDirectMaxSegments segments are rendered by the shared direct pass (pt sample batches after
// the chains: isDirectUnit / runDirectUnit of mlt_job.h, layer 0, P / N at develop). The chains' space is
// the longer paths only (PathSpace minEdges = chainMinLength(s) = 3: f = 0 on the shorter, so moves to them
// are rejected), and their b, bootstrap candidates and start strategies leave the direct paths out as
// mmlt's do (EvaluatorPssTarget with separateDirect; startPathFromSample skips those strategies).
// Light views (light_view.h; on unless veach-light-view is 0): the paths E S* L are not in the chains'
// space either (PathSpace withoutLightViews, BdptEvaluator dropLightViews for the candidates and b
// samples); every chain also renders its share of the light-view pass's camera samples into
// lightViewLayer(), developed with P / N_merged. When nothing but light views carries light (the chains'
// b is 0: no chain to carry the pass), the plan is made again with the pass off and says so.
// Scenes: area, point and spot lights (path.h: a point or spot light is x_0 of counting measure);
// directional and environment lights are refused at plan time, naming the light.
// Not supported: Kelemen MIS splatting (refused by validation; expected values are veach-mlt's default).
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
std::vector<Color> developVeachImage(const JobPlan& plan, const PartialResult& merged, const MutationSettings& mutations);
// Independent samples of b a chain of `mutations` mutations evaluates (one per 64 mutations, rounded up).
uint64_t veachBSamples(uint64_t mutations);

// Per-mutation acceptance for logs and metadata: "bidir 0.412 (123/456), lens ..." over the merged stats.
std::string acceptanceSummary(const ChainStats& stats);

}  // namespace mlt::veach
