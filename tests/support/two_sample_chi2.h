// Two-sample chi-square test of homogeneity, for probabilistic inverses (Bitterli et al. 2017, sec. 5):
// "the inverse of a uniform u is uniform again" is checked without knowing the forward routine's
// success region S by comparing two independent samples, A = the u's on which the forward routine
// succeeds (uniform on S) and B = the inverted numbers of independent forward samples (uniform on S if
// the inverse is right), binned on a grid over [0,1)^d. Statistic (unequal sizes Na, Nb):
//   X^2 = sum_i (sqrt(Nb/Na) a_i - sqrt(Na/Nb) b_i)^2 / (a_i + b_i),  dof = (used bins) - 1,
// bins with a_i + b_i < 10 pooled into one. Passes when p > 1 - (1 - significance)^(1 / testCount).
#pragma once
#include <string>
#include <vector>

namespace mlt::test {

struct TwoSampleResult {
  bool passed = false;
  double pValue = 0, statistic = 0;
  int dof = 0;
  std::string message;
};

// Points are rows of `dims` coordinates in [0,1); each axis is cut into binsPerAxis bins.
TwoSampleResult twoSampleChi2(const std::vector<float>& a, const std::vector<float>& b, int dims, int binsPerAxis,
                              double significance = 0.01, int testCount = 1);

}  // namespace mlt::test
