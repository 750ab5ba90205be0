// b_1 of a per-length method (mmlt, rjmlt) from camera rays: the emission seen directly.
//
// Length 1 is a camera ray that hits a light (or escapes to an environment light). Its chains' target
// c_1 (target.h: the luminance of the path's contribution, (s, t) chosen at random and MIS-weighted)
// integrates over the primary samples to
//     b_1 = E_u[c_1(u)] = (1/P) sum_j I_j,   I_j = lum of the length-1 image in pixel j       (E1)
// whatever technique renders it. The bootstrap's candidates estimate it with the technique choice and
// the light-tracing technique (1, 1) in the way, and chains of length 1 get ~3% of the mutations, so
// their large steps hardly refine it: on the Cornell box at 256x256, b_1 (44% of b) kept 1.1% run-to-run
// spread at 32 mutations per pixel and ~0.45% at an 8 s job, most of mmlt's brightness error
// (docs/CHAINS.md).
//
// Here (E1) is estimated cell by cell with camera rays (pt limited to one segment: Le at the first hit,
// no next-event estimation). A cell is a pixel, or a G x G part of one where the film has fewer than
// kEmissionMinCells pixels (a small film's light would otherwise cover a few cells, all of them outline).
// Below, "pixel" j means cell j. Two stages:
//   1. a pilot: one ray per pixel;
//   2. pixel j gets n_j fresh rays in two independent replicates of n_j / 2 rays, each replicate
//      stratified over the pixel (stratifiedPixelPoint), and I_j^ is the mean of the replicates' means
//      m_j0, m_j1: n_j = kEmissionFlatRays where the pilot's 3x3 neighbourhood of j is one value (inside
//      a light or away from every light), else n_j = kEmissionEdgeRays (a light's outline, a textured
//      light), fewer if the outlines would take more than kEmissionEdgeBudget rays per pixel of the film.
// n_j depends on the pilot only and stage 2's rays are independent of it, so E[I_j^] = I_j: unbiased.
// The variance sits where a light's outline crosses a pixel; there stratified rays leave ~n^-1.5 of one
// ray's variance instead of n^-1. Var(b_1^) = (1/P^2) sum_j Var(I_j^), each estimated without bias by
// (m_j0 - m_j1)^2 / 4 (the replicates are i.i.d.; the sample variance of stratified rays would overstate
// it ~5x on the Cornell box). On the Cornell box at 256x256 this costs
// ~3 rays per pixel, ~0.1 s of one thread. The chains still render length 1 (their visits follow the
// brightness, which suits a light's outline better than pixel samples do); only the factor b_1 that
// scales them comes from here. Except where a light is small on the film (smallLightCells below): there
// length 1's chains cannot share the light out among the lights, and --direct-light auto renders length 1
// by a pass of its own (DirectLight::Emission, mlt_job.h), so this estimate is not made.
#pragma once
#include <cstdint>
#include <vector>

#include "common/mlt/importance.h"
#include "common/mlt/target.h"
#include "common/mlt/target_sums.h"
#include "common/settings/render_settings.h"

namespace mlt {

class RenderScene;

constexpr uint32_t kEmissionFlatRays = 2;   // two replicates of one ray: a pixel the pilot misread shows its variance
constexpr uint32_t kEmissionEdgeRays = 256;  // even
constexpr double kEmissionEdgeBudget = 4;   // rays per cell for the outlines, at most
constexpr uint64_t kEmissionMinCells = uint64_t(1) << 16;
// A light about a cell wide is what the pilot reads worst: its one ray per cell hits the light or misses
// it, and either way the 3x3 test cannot find the outline (a cell that missed looks like dark space, one
// that hit like a bright cell among its equals' neighbours only by chance). So the light's geometry marks
// its cells: kFootprintPoints points of every area light (stratified over sampleLe's position numbers),
// projected onto the film through the lens centre; a light whose points land in at most
// kFootprintMaxCells cells is small, and those cells and their 8 neighbours get the outline's count of rays
// whatever the pilot saw (smallLightCells). A larger light covers enough cells for the pilot to see it.
// The marks are a pure function of the scene, independent of the stage-2 rays, so the estimate stays
// unbiased (a thin-lens camera's blur or an occluder only makes a mark cost rays it did not need).
// glossy-plates' four spheres of equal power (radius 0.03 to 0.9, the smallest ~1 pixel wide at 256x256,
// radiance 1111) each hold a quarter of b_1: without the marks the pilot's cell on the smallest held ~25% of
// its emission (or, missed, left the cell "flat" with 2 rays), so b_1 came from the candidates and mmlt's
// large steps at ~7% standard error at 16 s, most of the image's brightness error there (docs/CHAINS.md).
// Where a cell the marks do not cover still holds kEmissionMaxCellShare or more of the pilot's emission (a
// long light thinner than a cell, which the marks leave to the pilot), or nothing is seen at all, the
// bootstrap keeps the candidates' b_1 (mlt_job_bootstrap.cpp); a uniform light of N cells holds 1/N per cell (the
// Cornell box's: 0.3%). The choice reads the pilot and the geometry only, which are independent of both
// estimates, so whichever is chosen stays unbiased.
// A scene of many lights gets fewer points per light (at least 64), kFootprintPointBudget in all: the
// marks are drawn by the bootstrap and by every unit of the emission pass (mlt_job_bootstrap.cpp, mlt_job_run.cpp).
constexpr uint32_t kFootprintPoints = 4096;
constexpr uint64_t kFootprintPointBudget = uint64_t(1) << 18;
constexpr uint64_t kFootprintMaxCells = 256;
constexpr double kEmissionMaxCellShare = 0.01;
// What one of these camera rays costs in the bootstrap's unit (numbers drawn by a candidate, bootstrap.h
// candidateCost), so that the bootstrap's budget counts them: measured on one thread at 256x256, a ray
// takes 214-249 ns (pilot alone on caustic-mirror; pilot and outlines on the Cornell box) and a
// candidate of length 1 (cost 5) 337-401 ns (bootstrap_cost_bench): about 3 units a ray.
constexpr double kEmissionRayCost = 3;

struct EmissionEstimate {
  bool estimated = false;   // false: the pilot alone ran (no emission seen, or kEmissionMaxCellShare reached)
  BootstrapEstimate estimate;
  // With a shaped target (a map or a power): `estimate` is of that target, this of b_1's luminance, from the
  // same rays (n = 0 otherwise).
  BootstrapEstimate luminance;
  uint64_t rays = 0;            // pilot + stage 2
  int cellsPerPixelAxis = 1;    // G
  uint64_t litCells = 0;        // cells whose pilot ray saw emission
  uint64_t smallLights = 0;     // lights whose footprint marked their cells (smallLightCells)
  double maxCellShare = 0;      // the largest pilot value of a cell not marked, over the pilot's sum
  uint64_t edgeCells = 0;       // cells given the outline's count
  uint32_t edgeRays = 0;        // rays of each such cell
};

// G, the cells per pixel axis of a width x height film: at least kEmissionMinCells cells in all.
int emissionCellsPerPixelAxis(int width, int height);
// The points per light of the footprints, per side of their square of uPos: sqrt(kFootprintPoints) = 64,
// fewer where the scene's area lights would draw more than kFootprintPointBudget points in all (at least 8).
int footprintPointsPerSide(const RenderScene& scene);
// The cells (G x G per pixel, row-major) marked by small lights' footprints, 1 = marked; *lights: how many
// lights marked some.
std::vector<uint8_t> smallLightCells(const RenderScene& scene, int G, uint64_t* lights = nullptr);

// (E1) for the scene camera's film, or only the pilot where it says the rays would sample b_1 badly
// (estimated = false: maxCellShare at least kEmissionMaxCellShare, or no emission seen and no small light). A pure function of (scene, settings.seed,
// settings.integrator). The estimate is of the whole b_1: no tail split (tau = infinity, so the chains'
// large steps of length 1 are summed whole too). Its sampleVar and bulkVar are left 0 for the caller: the
// variance of c_1 per uniform sample (the candidates', which run after this pilot decided whether they
// only seed chains) is what a large step of length 1 has and what combineB weighs the large steps by.
// target (optional): b_1 of the chains' target (common/mlt/target.h): with the relative target's map
// (1/P) sum_j h_j I_j, each cell's estimate weighted by its pixel's h; with a power beta each ray's
// (h L_e)^beta (T1). The pilot's decisions read the rays' luminance.
EmissionEstimate emissionEstimate(const RenderScene& scene, const RenderSettings& settings,
                                  const TargetShape& target = {}, bool parallel = true);

}  // namespace mlt
