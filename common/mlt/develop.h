// Normalization of Markov chain images, derived once, here.
//
// ---- One path length (pssmlt, pssmlt-bdpt) ------------------------------------------------------
// A path sample u in primary sample space U (unit volume) contributes splats f(u) to pixels; the film
// position comes from the camera stream and spans the whole film, so for pixel j (P pixels in all)
//     E_u[ f_j(u) ] = integral over U of f_j(u) du = I_j / P,
// where f_j is the part of the splats landing in pixel j and I_j the pixel value (the same units as a
// pixel sample of pt/bdpt; t = 1 splats included, cf. sample_job.cpp).
// A chain visits u with density c(u) / b, b = integral of c over U (the bootstrap's estimate). Both
// splatting schemes of chain.h give every mutation a total weight of 1 in units of f / c (in
// expectation), so over M mutations
//     E[ splatSum_j ] = M * integral of (c(u) / b) * f_j(u) / c(u) du = (M / b) * I_j / P,
// hence
//     I_j = b * P / M * splatSum_j,                                             (D1)
// with splatSum_j summed over all chains and M the total number of mutations (P / M = 1 / mpp).
//
// ---- Several path lengths (mmlt) ----------------------------------------------------------------
// Length k has its own target c_k, normalization b_k and M_k mutations; its image is (D1) with (b_k,
// M_k) and the image is the sum over k. With one splat buffer, every length must share one scale. We
// choose the global scale b * P / M (b = sum b_k, M = sum M_k) and let each chain of length k multiply
// its splat weights by
//     r_k = (b_k / M_k) / (b / M)                                               (D2)
// so that b * P / M * r_k * splatSum_k = b_k * P / M_k * splatSum_k exactly, whatever the allocation.
// Allocation apportions M_k proportionally to b_k (largest remainder), so r_k = 1 up to rounding of
// one mutation; (D2) removes even that. (D2) holds only for the planned M_k, so every planned chain must
// run: the farm waits for every chain, and a time budget chooses M before planning (from a throughput
// trial, tools/cli/render_local.cpp) instead of dropping chains. A preview of some chains develops with
// the mutations merged (approximate for mmlt).
//
// ---- Direct illumination rendered separately (separateDirect) -------------------------------------
// Paths of at most kDirectMaxSegments segments are rendered by bdpt (pixel samples + t = 1 splats) and
// the chains carry only longer paths. bdpt's pixel estimates use the film's pixel buffer (sum / count);
// its t = 1 splats would develop with P / N (N = light paths, see sample_job.cpp); they are pre-scaled by
//     (P / N) / (b P / M) = M / (b N)                                           (D3)
// when the unit finishes, so that one splat scale (D1) develops chains and direct pass together.
//
// ---- Exact merging ----------------------------------------------------------------------------------
// Each unit's sums are rounded to multiples of 2^-kQuantumExp (stochastic rounding with a hash of (job
// seed, unit, element): unbiased and deterministic). Sums of such values are exact in double while below
// 2^(53 - kQuantumExp), so partial results develop to identical bytes however units are grouped.
#pragma once
#include <cstdint>
#include <vector>

#include "common/film/film.h"

namespace mlt {

constexpr int kDirectMaxSegments = 2;  // separateDirect: emission seen directly (1) and one bounce (2)
constexpr int kQuantumExp = 26;

// (D1): the splat scale of the merged film.
double chainSplatScale(double b, uint64_t totalMutations, size_t pixels);
// (D2): the weight factor of a chain of length k.
double lengthWeightCorrection(double bk, uint64_t Mk, double b, uint64_t M);
// (D3): the pre-scale of the direct pass's t = 1 splats.
double directSplatPrescale(double b, uint64_t totalMutations, uint64_t directLightPaths);
// Rounds every sum of `film` to a multiple of 2^-kQuantumExp (see above). Values of 2^(52 - kQuantumExp)
// or more are multiples already and are kept as they are; where merged sums exceed 2^(53 - kQuantumExp)
// the last bits may depend on the grouping (the image is still right, and deterministic per grouping).
void quantizeFilm(Film& film, uint64_t jobSeed, uint64_t unitIndex);

}  // namespace mlt
