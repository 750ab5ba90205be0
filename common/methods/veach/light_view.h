// The light-view pass of veach-mlt: the paths E S* L (a light seen by the lens directly, or through
// mirrors and glass; every vertex between the light and the lens specular) rendered by camera rays, and
// left out of the chains' path space.
//
// Why apart. Such a path has no diffuse vertex, so none of Veach's moves explores it well: only the lens
// perturbation applies, and it must land its new film point inside the light's image. A small light
// imaged by a glass sphere in a mirror (caustic-mirror) has an image smaller than the smallest lens step
// (0.1 pixel): every proposal misses, and the chains the start resampling sent there (in proportion to a
// rare bootstrap candidate's c) never leave, so that pixel gets the variance of the bootstrap's few
// thousand candidates (docs/VEACH.md, "The paths, traced": 93-99% of the worst runs' error). A camera ray
// that follows Dirac lobes is the one strategy of bdpt that makes these paths at all (every other one
// would connect at a Dirac vertex: bdpt's MIS weight of s = 0 is 1 there), and it is cheap: one ray per
// vertex, nothing to connect. So the chains' f is zero on light views (PathSpace withoutLightViews), the
// bootstrap's and the b samples' bdpt leaves them out (BdptEvaluator dropLightViews, whose c then
// integrates the chains' f), and this pass renders exactly them: the two partition path space.
//
// The pass: sppLV = max(1, round(ratio x mutations per pixel)) samples per pixel (ratio: the parameter
// veach-light-view, 0 = off, the chains then carry these paths as before). Its N = P sppLV samples are
// numbered i = 0 .. N - 1; sample i lies in pixel (i a) mod P (a coprime to P, so every pixel gets exactly
// sppLV of them, spread over the film in index order), at the pixel's Sobol point k = i / P
// (sobolPixelPoint: a pixel's sppLV samples stratified over it), and draws its lens point and lobe choices
// from a generator seeded by (job seed, i) alone. The chains carry them: the chain of global
// mutations [C_u, C_u + M_u) (C_u: the mutations of the chains before it, M in all) takes samples
// [ceil(C_u N / M), ceil((C_u + M_u) N / M)), so the pass's cost follows each chain's length (a time
// budget's throughput trial, running prefixes of chains, measures it with them) and the ranges tile
// [0, N) once every chain is in. The samples splat L (a pixel estimate) into film layer lightViewLayer(),
// developed with P / N_merged (N_merged: the samples of the chains merged; 1 / sppLV once all are).
// Deterministic in the job seed and independent of how the chains are grouped into tasks.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "common/core/color.h"
#include "common/core/rng.h"
#include "common/core/vec.h"
#include "common/job/job_types.h"

namespace mlt {
class SparseSplatter;
namespace veach {

class PathSpace;

// Samples per pixel of the pass (0: no pass).
uint32_t lightViewSpp(double ratio, double mutationsPerPixel);
// The film layer the pass splats into (after veach-mlt's chain and strata layers).
size_t lightViewLayer();
// Samples [first, second) of the pass carried by chain `unit` of `plan` (sppLV samples per pixel). A unit
// with fewer mutations than the plan gives it (a time budget's trial prefix) takes the start of its range,
// in proportion.
std::pair<uint64_t, uint64_t> lightViewRange(const JobPlan& plan, const WorkUnit& unit, uint32_t sppLV);
// The pixel sample i lies in: (i a) mod pixels, a coprime to pixels.
uint64_t lightViewPixel(uint64_t i, uint64_t pixels);
// One camera sample through film point pRaster: the radiance of the lights it sees through Dirac lobes
// only (E S* L with between space.minEdges() and space.maxEdges() edges), bdpt's s = 0 estimate of those
// paths (throughput f cos / pdf per lobe, no roulette).
Color lightViewRadiance(const PathSpace& space, Vec2 pRaster, Pcg32& rng);
// Renders the unit's samples (lightViewRange) into `splatter` (layer lightViewLayer()).
void renderLightViews(const PathSpace& space, const JobPlan& plan, const WorkUnit& unit, uint32_t sppLV,
                      SparseSplatter& splatter);
// The develop scale of the pass's layer for the units merged: P / (their samples), 0 without samples.
double lightViewScale(const JobPlan& plan, const std::vector<uint32_t>& mergedUnits, uint32_t sppLV);

}  // namespace veach
}  // namespace mlt
