// KelemenSource: exact restore on reject, replay of the start candidate, determinism, divergence of
// chains that share a start candidate, and lazy mutation == eager mutation in distribution.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "common/core/rng.h"
#include "common/mlt/kelemen_source.h"
#include "common/sampler/sample_source.h"
#include "tests/support/chi2.h"

namespace mlt {
namespace {

constexpr uint64_t kSeed = 77;

bool bitEqual(const std::vector<float>& a, const std::vector<float>& b) {
  // (memcmp of an empty vector's data() would pass a null pointer: undefined, UBSan reports it)
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

void readBlock(KelemenSource& s, Stream stream, int n) {
  s.startStream(stream);
  for (int i = 0; i < n; ++i) s.next1D();
}

TEST(KelemenSource, StartStateReplaysTheCandidate) {
  KelemenSource s(KelemenParams{}, kSeed, 3, 12345);
  const IndependentSource candidate = IndependentSource::candidate(kSeed, 12345);  // the bootstrap's source
  for (int stream = 0; stream < kNumStreams; ++stream) {
    s.startStream(Stream(stream));
    for (int j = 0; j < 40; ++j) EXPECT_EQ(s.next1D(), candidate.valueAt(stream, j)) << stream << " " << j;
  }
  // Reading again in the same iteration returns the same numbers.
  s.startStream(Stream::Light);
  s.seek(7);
  EXPECT_EQ(s.next1D(), candidate.valueAt(1, 7));
}

TEST(KelemenSource, RejectRestoresEveryCoordinateExactly) {
  for (SmallStepKernel kernel : {SmallStepKernel::Kelemen, SmallStepKernel::Gaussian}) {
    KelemenParams p;
    p.kernel = kernel;
    p.largeStepProb = 0.3f;
    KelemenSource s(p, kSeed, 0, 1);
    readBlock(s, Stream::Camera, 10);
    readBlock(s, Stream::Light, 5);
    s.accept();
    Pcg32 decide(5, 5);
    for (int it = 0; it < 2000; ++it) {
      std::vector<float> before[kNumStreams];
      for (int st = 0; st < kNumStreams; ++st) before[st] = s.storedValues(st);
      const int64_t iteration = s.iteration();
      s.startIteration();
      // Read a varying number of coordinates, often beyond what was ever read (the vectors grow).
      readBlock(s, Stream::Camera, 4 + int(decide.bounded(40)));
      readBlock(s, Stream::Light, int(decide.bounded(30)));
      if (decide.uniform() < 0.3f) readBlock(s, Stream::Connect, int(decide.bounded(10)));
      if (decide.uniform() < 0.5f) {
        s.accept();
        continue;
      }
      s.reject();
      EXPECT_EQ(s.iteration(), iteration);
      for (int st = 0; st < kNumStreams; ++st) {
        std::vector<float> after = s.storedValues(st);
        // Coordinates first created by the rejected proposal are "never read" again: compare the prefix
        // that existed, and check reading continues to work.
        ASSERT_GE(after.size(), before[st].size());
        after.resize(before[st].size());
        ASSERT_TRUE(bitEqual(after, before[st])) << "iteration " << it << " stream " << st;
      }
    }
  }
}

TEST(KelemenSource, RejectedCoordinatesAreCurrentAgainAfterward) {
  // After a rejected proposal, a small step moves each coordinate from its committed value by one step.
  KelemenParams p;
  p.largeStepProb = 0;
  KelemenSource s(p, kSeed, 0, 9);
  readBlock(s, Stream::Camera, 8);
  s.accept();
  const std::vector<float> committed = s.storedValues(0);
  s.startIteration();
  readBlock(s, Stream::Camera, 8);
  s.reject();
  s.startIteration();
  s.startStream(Stream::Camera);
  for (int j = 0; j < 8; ++j) {
    float d = std::fabs(s.next1D() - committed[j]);
    d = std::fmin(d, 1 - d);  // wrap-around distance
    EXPECT_LE(d, p.s2 * 1.0001f) << j;
    EXPECT_GE(d, p.s1 * 0.999f) << j;
  }
}

std::vector<float> trajectory(uint64_t chain, uint64_t candidate, int iterations) {
  KelemenParams p;
  KelemenSource s(p, kSeed, chain, candidate);
  readBlock(s, Stream::Camera, 6);
  s.accept();
  std::vector<float> out;
  Pcg32 decide(1, 2);
  for (int it = 0; it < iterations; ++it) {
    s.startIteration();
    s.startStream(Stream::Camera);
    for (int j = 0; j < 6; ++j) out.push_back(s.next1D());
    if (decide.uniform() < 0.5f) s.accept();
    else s.reject();
  }
  return out;
}

TEST(KelemenSource, SameSeedSameSequence) { EXPECT_TRUE(bitEqual(trajectory(4, 100, 500), trajectory(4, 100, 500))); }

TEST(KelemenSource, ChainsFromTheSameCandidateDiverge) {
  const std::vector<float> a = trajectory(4, 100, 50), b = trajectory(5, 100, 50);
  int equal = 0;
  for (size_t i = 0; i < a.size(); ++i) equal += a[i] == b[i];
  EXPECT_EQ(equal, 0) << "two chains from one candidate share " << equal << " of " << a.size() << " numbers";
}

// Lazy == eager: coordinate 0 is read every iteration (eager) or only at the end (lazy). All proposals
// are accepted small steps, except a forced large step at iteration `largeAt` (0 = none). The final
// offset (v_T - v_0) mod 1 must have the same distribution: two-sample chi-square test.
double lazyEagerPValue(SmallStepKernel kernel, int T, int largeAt) {
  const int chains = 20000, bins = 100;
  std::vector<double> eager(bins, 0), lazy(bins, 0);
  KelemenParams p;
  p.kernel = kernel;
  p.sigma = 0.01f;
  for (int mode = 0; mode < 2; ++mode) {
    for (int c = 0; c < chains; ++c) {
      KelemenSource s(p, kSeed, uint64_t(c) + uint64_t(mode) * chains, 42);
      const float v0 = s.read(0, 0);
      s.read(0, 1);
      s.accept();
      for (int it = 1; it <= T; ++it) {
        s.startIteration(it == largeAt ? MutationType::Large : MutationType::Small);
        s.read(0, 1);  // something is always read
        if (mode == 0 || it == T) s.read(0, 0);
        s.accept();
      }
      double d = double(s.read(0, 0)) - v0;
      d -= std::floor(d + 0.5);  // in [-0.5, 0.5)
      const int bin = std::min(bins - 1, int((d + 0.5) * bins));
      (mode == 0 ? eager : lazy)[bin] += 1;
    }
  }
  double stat = 0;
  int dof = -1;
  for (int i = 0; i < bins; ++i) {
    if (eager[i] + lazy[i] < 10) continue;
    stat += (eager[i] - lazy[i]) * (eager[i] - lazy[i]) / (eager[i] + lazy[i]);
    ++dof;
  }
  return test::chi2SurvivalProbability(stat, dof);
}

TEST(KelemenSource, LazyMutationEqualsEagerInDistribution) {
  const double alpha = 1 - std::pow(0.99, 1.0 / 4);
  EXPECT_GT(lazyEagerPValue(SmallStepKernel::Kelemen, 40, 0), alpha);
  EXPECT_GT(lazyEagerPValue(SmallStepKernel::Gaussian, 40, 0), alpha);
  EXPECT_GT(lazyEagerPValue(SmallStepKernel::Kelemen, 40, 25), alpha);
  EXPECT_GT(lazyEagerPValue(SmallStepKernel::Gaussian, 40, 25), alpha);
}

TEST(KelemenSource, RejectsBadParameters) {
  KelemenParams p;
  p.largeStepProb = 1.5f;
  EXPECT_THROW(KelemenSource(p, 1, 1, 1), std::invalid_argument);
  p = KelemenParams{};
  p.s1 = 0.1f;
  p.s2 = 0.01f;
  EXPECT_THROW(KelemenSource(p, 1, 1, 1), std::invalid_argument);
  p = KelemenParams{};
  p.kernel = SmallStepKernel::Gaussian;
  p.sigma = 0;
  EXPECT_THROW(KelemenSource(p, 1, 1, 1), std::invalid_argument);
}

}  // namespace
}  // namespace mlt

// IndependentSource reads hashUniform(seed, index, stream, coordinate) through HashPrefix2 (rng.h): the
// same bits, including seeds and indices with high bits set, coordinates past the table, resets.
TEST(IndependentSource, ValuesAreHashUniformBitForBit) {
  mlt::Pcg32 rng(7, 11);
  for (int trial = 0; trial < 200; ++trial) {
    const uint64_t seed = (uint64_t(rng.nextU32()) << 32) | rng.nextU32();
    const uint64_t index = trial % 3 == 0 ? uint64_t(trial) : (uint64_t(rng.nextU32()) << 32) | rng.nextU32();
    mlt::IndependentSource source(1, 2);
    source.reset(seed, index);
    for (int stream = 0; stream < 4; ++stream)
      for (int c : {0, 1, 2, 5, 63, 64, 65, 200, 100000}) {
        const float want = mlt::hashUniform(seed, index, uint64_t(stream), uint64_t(c));
        ASSERT_EQ(source.valueAt(stream, c), want) << "seed " << seed << " index " << index << " stream " << stream
                                                   << " coordinate " << c;
      }
    for (uint64_t c : {uint64_t(0), uint64_t(63), uint64_t(64), ~uint64_t(0)})
      ASSERT_EQ(mlt::HashPrefix2(seed, index)(3, c), mlt::hashKeys(seed, index, uint64_t(3), c));
  }
}
