// Alias table (Walker 1977, Vose 1991): O(1) sampling of index i with probability w_i / sum(w).
// Built deterministically (fixed order of the small/large work lists), so the same weights give the
// same table on every machine.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mlt {

class AliasTable {
 public:
  AliasTable() = default;
  // Weights must be finite and >= 0 with a positive sum (throws std::invalid_argument otherwise).
  explicit AliasTable(const std::vector<double>& weights);
  // Index for a uniform u in [0, 1).
  uint64_t sample(double u) const;
  // Probability of index i (w_i / sum w).
  double pmf(uint64_t i) const { return pmf_[i]; }
  size_t size() const { return prob_.size(); }
  double sum() const { return sum_; }

 private:
  std::vector<double> prob_;     // probability of keeping bin i
  std::vector<uint64_t> alias_;  // the other index in bin i
  std::vector<double> pmf_;
  double sum_ = 0;
};

}  // namespace mlt
