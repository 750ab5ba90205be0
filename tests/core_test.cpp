#include <gtest/gtest.h>

#include "common/core/rng.h"
#include "common/core/transform.h"
#include "common/sampler/sample_source.h"

namespace mlt {

TEST(Transform, InverseComposesToIdentity) {
  const Transform t = Transform::translate({1, 2, 3}) * Transform::rotate({0.3f, 1, 0.2f}, 37) *
                      Transform::scale({2, 0.5f, 3});
  const Transform id = t * t.inverse();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(id.m[i][j], i == j ? 1.0 : 0.0, 1e-12);
}

TEST(Transform, SingularThrows) { EXPECT_THROW(Transform::scale({1, 0, 1}).inverse(), std::runtime_error); }

TEST(IndependentSource, RandomAccessMatchesSequentialReads) {
  IndependentSource a(42, 7), b(42, 7);
  a.startStream(Stream::Light);
  std::vector<float> seq;
  for (int i = 0; i < 10; ++i) seq.push_back(a.next1D());
  for (int i = 9; i >= 0; --i) EXPECT_EQ(b.valueAt(int(Stream::Light), i), seq[i]);
  IndependentSource c(42, 8);
  c.startStream(Stream::Light);
  EXPECT_NE(c.next1D(), seq[0]);
}

TEST(Pcg32, UniformMeanAndRange) {
  Pcg32 rng(1, 2);
  double sum = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const float u = rng.uniform();
    ASSERT_GE(u, 0.0f);
    ASSERT_LT(u, 1.0f);
    sum += u;
  }
  // Standard error of the mean of U(0,1) is sqrt(1/12/n); allow 5 sigma.
  EXPECT_NEAR(sum / n, 0.5, 5 * std::sqrt(1.0 / 12 / n));
}

}  // namespace mlt
