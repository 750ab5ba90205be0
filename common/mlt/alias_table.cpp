#include "common/mlt/alias_table.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace mlt {

AliasTable::AliasTable(const std::vector<double>& weights) {
  const size_t n = weights.size();
  if (n == 0) throw std::invalid_argument("AliasTable: no weights");
  sum_ = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(weights[i]) && weights[i] >= 0))
      throw std::invalid_argument("AliasTable: weight " + std::to_string(i) + " is " + std::to_string(weights[i]));
    sum_ += weights[i];
  }
  if (!(sum_ > 0)) throw std::invalid_argument("AliasTable: all weights are zero");
  prob_.assign(n, 0);
  alias_.assign(n, 0);
  pmf_.resize(n);
  // Vose's method: scaled weights q_i = n w_i / sum; pair each small (q < 1) with a large (q >= 1).
  std::vector<double> q(n);
  std::vector<uint64_t> small, large;
  small.reserve(n);
  large.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    pmf_[i] = weights[i] / sum_;
    q[i] = pmf_[i] * double(n);
    (q[i] < 1 ? small : large).push_back(i);
  }
  while (!small.empty() && !large.empty()) {
    const uint64_t s = small.back(), l = large.back();
    small.pop_back();
    large.pop_back();
    prob_[s] = q[s];
    alias_[s] = l;
    q[l] = (q[l] + q[s]) - 1;
    (q[l] < 1 ? small : large).push_back(l);
  }
  // Leftovers are 1 up to rounding.
  for (uint64_t i : large) { prob_[i] = 1; alias_[i] = i; }
  for (uint64_t i : small) { prob_[i] = 1; alias_[i] = i; }
}

uint64_t AliasTable::sample(double u) const {
  const double scaled = u * double(prob_.size());
  uint64_t i = static_cast<uint64_t>(scaled);
  if (i >= prob_.size()) i = prob_.size() - 1;
  const double up = scaled - double(i);  // uniform in [0,1) again
  return up < prob_[i] ? i : alias_[i];
}

}  // namespace mlt
