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
// Length k has its own target c_k, normalization b_k and M_k mutations; its image is (D1) with (b_k, M_k)
// and the image is the sum over k:
//     I_j = sum_k b_k * P / M_k * splatSum_kj.                                 (D2)
// Every length splats into its own film layer (film.h: chainLayer(k) = 1 + 2k; pssmlt's single length is
// slot 0, layer 1), so the chains never see b_k: the factor is applied once, here, when the image is developed.
// M_k is the number of mutations of length k merged, so a preview of some chains is (D2) over what it
// holds (each chain is stationary; a subset of chains estimates its lengths' images) and exact.
//
// ---- b refined as the job runs ---------------------------------------------------------------------
// b_k = integral over U of c_k(u) du. Two sets of samples of c_k estimate it:
//  - N_0 bootstrap candidates. Each is uniform on U on its own, but their film positions (Camera
//    [0,1]) are a randomized Halton sequence in kCandidateGroups independent randomizations
//    (sample_source.h), so the image's bright and dark regions are visited in proportion. Their mean b_0
//    is unbiased for a count fixed in advance; a budgeted bootstrap of several lengths grows each by its
//    values after the first round (optional stopping: b_0 of all of them leaned low, by 3.7% on
//    cornell-spheres' mmlt), so N_0 is the first round's (bootstrap.h, LengthBootstrap::fixedCount; one
//    length keeps every candidate, its doublings depend on cost alone); its variance v_0 is estimated
//    from the spread of the groups' means (the i.i.d. formula would miss the gain: on the Cornell box
//    with its light in view, 6x smaller standard error);
//  - every large step of every chain of length k: it draws all of its coordinates afresh, independently
//    of the chain's state, whether accepted or not, so its c(y) is an i.i.d. uniform sample. Their mean
//    b_L = S_L / N_L (S = sum of c, merged by addition) has variance sigma^2 / N_L, where sigma^2, the
//    variance of c for one uniform sample, is estimated by the bootstrap (its i.i.d. sample variance).
// Split at the bootstrap's tail threshold tau (its tailCandidates(N_0)-th largest c, about 1 in 1024):
// c = m + e with the bulk m = min(c, tau) and the excess e = max(c - tau, 0). Every sample's m and e are
// summed apart (TargetSums; the chains know tau from the plan), and
//     b_k^ = [w m_0 + (1 - w) m_L] + (N_0 e_0 + N_L e_L) / (N_0 + N_L),
//     w = v_L / (v_0 + v_L),  v_0 = the groups' variance of m_0,  v_L = Var(m) / N_L,          (D3)
// the bulk by inverse variance (it keeps the bootstrap's stratification gain: the light seen directly,
// 6x), the excess pooled by count. SE(b_k^)^2 = w^2 v_0 + (1 - w)^2 max(v_L, S2_L / N_L) + Var(e^)
// + 2 Cov(m^, e^), with S2_L the large steps' own spread of m (a tail the bootstrap never saw shows there)
// and Cov = E[e] (tau - E[m]) / N (target_sums.h).                                                 (D4)
// Why the split: weights estimated from the bootstrap depend on its values. A bootstrap that missed the
// rare bright paths has a small spread and a low mean and gets more weight, one that caught them less:
// inverse-variance weights on all of c (the rule before) biased b low by 0.2-1.3% on heavy-tailed targets
// (tests/mlt_refine_test.cpp, RefinedB.CombinedBIsUnbiasedForAHeavyTailedStratifiedTarget: -1.3%; the
// chain methods' brightness on the results page leaned low). The bulk is bounded by tau, so its weights
// hardly move with a tail hit, and the excess's weights are counts: the test measures no bias left
// (tau itself is a bootstrap value; the bias it leaves is below the test's 0.04% resolution).
// Pooling all of c by count would be unbiased too, but loses the bulk's stratification gain (on the Cornell
// box's b_1, 0.0029 -> 0.0042). With no large steps b_k^ = b_0; as the job grows w -> 0 and b_k^ -> the
// large steps' mean: the brightness error shrinks with the job instead of staying at the bootstrap's. (D5)
// The large steps' bulk is post-stratified by film position (common/mlt/strata.h): each chain of a
// one-length method (pssmlt, pssmlt-bdpt; veach-mlt's b samples alike) keeps, per pixel of its Camera[0,1]
// coordinates, the count and sums of its large steps' m in film layer bStrataLayer(k), and m_L in (D3) is
// the quadtree post-stratified mean of those layers, v_L its estimated variance (D6). mmlt and rjmlt keep
// none (mlt_job_run.cpp: no gain on their brightness, 10% of their throughput). Where c varies mostly with the pixel (light or bright walls seen directly) this removes
// most of the large steps' variance (the bootstrap's Halton positions do the same for m_0); elsewhere it
// changes little. The two bulks are then weighted by count, w = N_0 / (N_0 + N_L): both are stratified by
// film position, and weights from the strata's own variance estimate (which moves with their mean where few
// samples share a stratum) biased b low, by 16% on a small Cornell box (tests/mlt_bundled_test.cpp). The
// strata's estimated variance enters SE(b_k^) in place of v_L.                                       (D6)
// b = sum_k b_k^, SE(b) = sqrt(sum_k SE(b_k^)^2) (independent lengths).
// (Using b_k^ from the same run as the splats makes I_j a ratio estimator, biased by O(1/N): negligible
// beside its noise at the millions of large steps of a real job.) Kelemen's MIS splatting weights with the
// bootstrap's b_k, which the chain must know; the large steps' share of its splats is developed with that
// same b_k, in a layer of its own (D7), so that an error of the bootstrap's b_k moves only the weights.
//
// ---- A relative target: the image's brightness from luminance (importance.h) --------------------------
// With c = sum of lum(f_i) h_i the development above is still unbiased, but the image's total luminance
// is no longer b: with c = lum(f) every visit carries lum(f) / c = 1, so the image mean is b's however the
// chains spread over the film, while with c_h a visit carries 1 / h of its pixel, and the image mean
// follows where the chains happen to be. Measured on a 24x24 Cornell box (mmlt, 12 runs): per-run image
// means 2.4% apart with 256 chains (the luminance target: 0.1%), 30% apart with 16 chains and a noisier map.
// So each slot's image is scaled to the luminance b_lum,k = E_u[lum(f_k(u))] that uniform samples estimate:
//     I_kj = (P b_lum,k^ / sum_j' lum(I~_kj')) I~_kj,     I~ = the slot's image developed as above,  (D8)
// b_lum,k^ pooled from the bootstrap's luminance (each candidate's, next to its c; b_1's camera rays
// unweighted) and the large steps' luminance sums by (D3)-(D5) without strata. The chains then decide only
// how the light is shared between pixels, b_lum the brightness: the brightness error is b_lum^'s, as it is
// with the luminance target. A ratio estimator: biased by O(1/N), negligible at a job's millions of samples.
//
// ---- Rao-Blackwellized b samples (mmlt, rjmlt: --b-sample-every N) ------------------------------------
// mmlt's c_k(u) = n w_{s,t} lum(C_{s,t}) evaluates the one technique that a coordinate u_tech of u picks
// uniformly among the n = k + 1 of length k; nothing else reads u_tech. Averaging over it, the rest of u
// held,
//     c^_k(u) = E[c_k | u without u_tech] = sum_{s+t=k+1} w_{s,t} lum(C_{s,t}),     E_u[c^_k] = b_k,   (D9)
// every technique on the same numbers (bdpt.h, evaluateLength), so Var c^_k <= Var c_k (Rao-Blackwell). A
// path that one technique samples far better than the others (on caustic-mirror the camera subpath that
// reaches the small light) is worth n times its share in c_k once in n draws, and its share once in c^_k:
// the heavy tail of c_k's large steps is n times lighter. With N > 0 each chain of a length k with n > 1
// also evaluates c^_k at ceil(M / N) points of its own stream (M its mutations; independent of the chain
// and of the plan's candidates, a count fixed by the plan), and b_k is (D3) over those samples alone: the
// plan keeps no bootstrap estimate for such a length (Normalization::bootstrapB[k].n = 0), and the large
// steps' c is not used for b (their sums are not kept). Unbiased like (D3) (no value decides a count or a
// weight). Measured (docs/CHAINS.md): c^ costs ~2.3 mutations; on caustic-mirror with N = 4 the brightness
// spread over seeds halves (sd 4.2% -> 2.2%) and its median moves from -2.75% to -0.8%, for 1.6x the time;
// with N = 32 it widens (6.5%): fewer samples than the large steps, whose tail is n times heavier but whose
// count is p_large M. So the default is 0, the large steps (equal-time error first).
//
// ---- Direct illumination rendered separately (separateDirect) -------------------------------------
// Paths of at most kDirectMaxSegments segments are rendered by a sample job (kDirectPassMethod, pt: pixel
// samples; a bdpt pass would add t = 1 splats) and the chains carry only longer paths. Pixel estimates use
// the film's pixel buffer (sum / count); t = 1 splats go to layer 0 and develop with P / N (N = light paths
// merged, see sample_job.cpp).
//
// ---- Exact merging ----------------------------------------------------------------------------------
// Each unit's sums are rounded to multiples of 2^-kQuantumExp (stochastic rounding with a hash of (job
// seed, unit, element): unbiased and deterministic). Sums of such values are exact in double while below
// 2^(53 - kQuantumExp), so partial results develop to identical bytes however units are grouped.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "common/film/film.h"
#include "common/film/sparse_splats.h"
#include "common/mlt/target_sums.h"

namespace mlt {

constexpr int kDirectMaxSegments = 2;  // DirectLight::Separate: emission seen directly (1) and one bounce (2)
constexpr int kQuantumExp = 26;

// (D1): the splat scale of one length's film layer.
double chainSplatScale(double b, uint64_t totalMutations, size_t pixels);
// The film layer of path length slot `slot` (pssmlt: 0; mmlt: k), and the layer of its large steps'
// strata (D6): per pixel (count, sum of m, sum of m^2), never part of the image (developed with scale 0).
inline size_t chainLayer(size_t slot) { return 2 * slot + 1; }
inline size_t bStrataLayer(size_t slot) { return 2 * slot + 2; }
// The largest film layer a job with `slots` path length slots fills.
inline size_t maxChainFilmLayer(size_t slots) { return bStrataLayer(slots == 0 ? 0 : slots - 1); }
// Kelemen MIS splatting (chain.h (K1)): the large steps' own share of slot's splats, in a layer after
// every chain and strata layer of a job of `slots` path length slots (plan.norm.mutationsPerLength.size()),
// developed with the b the chains weighted by (the bootstrap's b, or b_k), not the refined one.  (D7)
inline size_t largeStepLayer(size_t slot, size_t slots) { return maxChainFilmLayer(slots) + 1 + slot; }
// The splat layers a chain job's films hold: layer 0 (light-traced splats of a direct pass) and, per path
// length slot that has mutations, its chain layer and its strata layer, and with Kelemen MIS its
// large-step layer.
inline size_t chainFilmLayers(const std::vector<uint64_t>& mutationsPerSlot, bool largeStepLayers = false) {
  size_t layers = 1;
  for (uint64_t m : mutationsPerSlot) layers += m > 0 ? (largeStepLayers ? 3 : 2) : 0;
  return layers;
}

// Whether v is finite and a multiple of 2^-kQuantumExp (what quantizeFilm makes of every sum), read from
// its bits: v = 1.f x 2^e has significand bits of weight 2^(e-52+j), j = 0..52 (52 the implicit one), and
// is on the grid iff every bit of weight below 2^-kQuantumExp, j < 52 - kQuantumExp - e, is zero. Exact,
// and without libm (the coordinator checks every value of every uploaded film with it).
inline bool onQuantumGrid(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits &= ~(uint64_t(1) << 63);
  if (bits == 0) return true;
  const int biased = int(bits >> 52);
  if (biased == 0x7ff || biased == 0) return false;  // inf or NaN; subnormal (nonzero, below 2^-1022)
  if (biased - 1023 + kQuantumExp > 1023) return false;  // v x 2^kQuantumExp is not finite
  const int below = 52 - kQuantumExp - (biased - 1023);  // significand bits below the grid
  if (below <= 0) return true;
  if (below > 52) return false;  // even the implicit bit is below the grid
  return (bits & ((uint64_t(1) << below) - 1)) == 0;
}

// Rounds the sums of one work unit to multiples of 2^-kQuantumExp, as quantizeFilm does for films, so that
// they merge exactly in any grouping.
void quantizeSums(TargetSums& sums, uint64_t jobSeed, uint64_t unitIndex, uint64_t slot);
// Rounds every sum of `film` to a multiple of 2^-kQuantumExp (see above). Values of 2^(52 - kQuantumExp)
// or more are multiples already and are kept as they are; where merged sums exceed 2^(53 - kQuantumExp)
// the last bits may depend on the grouping (the image is still right, and deterministic per grouping).
void quantizeFilm(Film& film, uint64_t jobSeed, uint64_t unitIndex);
// The same rounding, with the same keys, for a unit's sparse splats: quantizing them and adding them to
// a zero film gives the film quantizeFilm gives the dense unit film.
void quantizeSplats(SparseSplats& splats, uint64_t jobSeed, uint64_t unitIndex);

}  // namespace mlt
