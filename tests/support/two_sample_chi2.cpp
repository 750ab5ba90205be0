#include "tests/support/two_sample_chi2.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "tests/support/chi2.h"

namespace mlt::test {

TwoSampleResult twoSampleChi2(const std::vector<float>& a, const std::vector<float>& b, int dims, int binsPerAxis,
                              double significance, int testCount) {
  TwoSampleResult r;
  int nBins = 1;
  for (int d = 0; d < dims; ++d) nBins *= binsPerAxis;
  auto histogram = [&](const std::vector<float>& pts, std::vector<double>& h, bool& outside) {
    h.assign(nBins, 0.0);
    for (size_t i = 0; i + dims <= pts.size(); i += dims) {
      int index = 0;
      for (int d = 0; d < dims; ++d) {
        const float u = pts[i + d];
        if (!(u >= 0 && u < 1)) outside = true;
        index = index * binsPerAxis + std::clamp(int(u * binsPerAxis), 0, binsPerAxis - 1);
      }
      h[index] += 1;
    }
  };
  std::vector<double> ha, hb;
  bool outside = false;
  histogram(a, ha, outside);
  histogram(b, hb, outside);
  const double na = double(a.size() / dims), nb = double(b.size() / dims);
  if (outside || !(na > 0) || !(nb > 0)) {
    r.message = outside ? "a point lies outside [0,1)^d" : "empty sample";
    return r;
  }
  const double ka = std::sqrt(nb / na), kb = std::sqrt(na / nb);
  double pooledA = 0, pooledB = 0;
  int used = 0;
  double worst = 0;
  int worstBin = -1;
  for (int i = 0; i < nBins; ++i) {
    if (ha[i] + hb[i] < 10) {
      pooledA += ha[i];
      pooledB += hb[i];
      continue;
    }
    const double t = ka * ha[i] - kb * hb[i];
    const double term = t * t / (ha[i] + hb[i]);
    if (term > worst) {
      worst = term;
      worstBin = i;
    }
    r.statistic += term;
    ++used;
  }
  if (pooledA + pooledB > 0) {
    const double t = ka * pooledA - kb * pooledB;
    r.statistic += t * t / (pooledA + pooledB);
    ++used;
  }
  r.dof = std::max(1, used - 1);
  r.pValue = chi2SurvivalProbability(r.statistic, r.dof);
  const double threshold = 1 - std::pow(1 - significance, 1.0 / testCount);
  r.passed = r.pValue > threshold;
  std::ostringstream m;
  m << "two-sample chi2 = " << r.statistic << ", dof = " << r.dof << ", p = " << r.pValue << " (threshold "
    << threshold << "), Na = " << na << ", Nb = " << nb << ", worst bin " << worstBin << " (a = "
    << (worstBin >= 0 ? ha[worstBin] : 0) << ", b = " << (worstBin >= 0 ? hb[worstBin] : 0) << ")";
  r.message = m.str();
  return r;
}

}  // namespace mlt::test
