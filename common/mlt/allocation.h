// How a chain job's mutations are shared among path lengths (mmlt, rjmlt: one set of chains per length),
// from the bootstrap's candidates. The plan allocates by these weights (mlt_job_plan.cpp), and the bootstrap's
// budget prices the chains' mix of lengths by the same weights (bootstrap.cpp, chainMixCost), so that
// a bootstrap sized as a share of the chains' time takes that share.
#pragma once
#include <cstdint>
#include <vector>

#include "common/core/vec.h"
#include "common/mlt/bootstrap.h"

namespace mlt {

// mmlt: mutations (and chains) per path length k in proportion to
//     b_k * sqrt(gbar_k),   gbar_k = sum_i c_i g(bin_i) / sum_i c_i   over length k's bootstrap candidates i,
// with g = 1 / (I^2 + kAllocationEps) of the image I (mean luminance) of the bin the candidate's light
// lands in, estimated from all candidates on kAllocationBinsPerAxis^2 bins of the film.
// Why: length k's chains with M_k mutations visit pixel j in proportion to I_kj / b_k; a pixel estimate
// b_k P / M_k * (visits) then has variance ~ tau_k b_k P I_kj / M_k (tau_k: the chains' correlation time),
// i.e. a relative squared error summed over pixels of V_k / M_k with V_k ~ tau_k b_k P sum_j I_kj g_j
// = tau_k (b_k P)^2 gbar_k. Minimizing sum_k V_k / M_k at sum_k M_k = M gives M_k ~ sqrt(V_k) = b_k
// sqrt(gbar_k) (equal tau_k assumed). With g constant this is the plain rule M_k ~ b_k; a length whose light
// lands on bright pixels (the light seen directly) needs fewer mutations for the same relative error.
// kAllocationEps is the evaluation harness's relMSE epsilon: the rule minimizes that metric (docs/CHAINS.md).
constexpr int kAllocationBinsPerAxis = 16;
constexpr double kAllocationEps = 1e-2;
uint32_t allocationBin(Vec2 pRaster, int width, int height);
// Weights per bootstrap length (`lengths` order); empty if the bootstrap is not binned or has one length
// (then the allocation is proportional to b_k).
std::vector<double> allocationWeights(const std::vector<LengthBootstrap>& lengths);
// The weights the plan allocates mutations by: allocationWeights, or b_k where those are empty.
std::vector<double> mutationWeights(const std::vector<LengthBootstrap>& lengths);

}  // namespace mlt
