// The throughput trial of a time-budgeted Markov chain render (tools/cli/render_local.cpp) takes its
// units in spreadIndex order: every prefix of 2^j runs lands once in each 1/2^j of the plan, so a short
// trial sees long and short path lengths in the plan's own mix instead of the first (cheapest) chains.
#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

#include "tools/cli/render_local.h"

namespace mlt::cli {
namespace {

TEST(TimeBudgetTrial, EveryPowerOfTwoPrefixVisitsEachEqualBlockOfThePlanOnce) {
  for (size_t n : {size_t(1), size_t(7), size_t(64), size_t(159), size_t(1000)}) {
    for (size_t runs = 1; runs <= 64 && runs <= n; runs *= 2) {
      std::vector<int> perBlock(runs, 0);
      for (size_t i = 0; i < runs; ++i) {
        const size_t u = spreadIndex(i, n);
        ASSERT_LT(u, n) << "n " << n << " run " << i;
        ++perBlock[u * runs / n];
      }
      for (size_t b = 0; b < runs; ++b)
        EXPECT_EQ(perBlock[b], 1) << "n " << n << ", first " << runs << " runs, block " << b;
    }
  }
}

TEST(TimeBudgetTrial, RunsBeyondThePlanStayInsideIt) {
  for (size_t i = 0; i < 4096; ++i) EXPECT_LT(spreadIndex(i, 3), size_t(3));
  EXPECT_EQ(spreadIndex(0, 159), size_t(0));
  EXPECT_EQ(spreadIndex(1, 159), size_t(80));  // the middle of the plan comes second (ceil(159 / 2))
}

}  // namespace
}  // namespace mlt::cli
