// KelemenSource: a Markov chain over the primary-sample vector with lazy mutation (Kelemen et al. 2002,
// sec. 4 and 6; the iteration bookkeeping follows pbrt-v3's MLTSampler).
//
// State. Every coordinate (stream s, index j) stores its value, the iteration it was last modified, and a
// backup of both. `iteration_` counts the accepted proposals ("time" in the paper; a rejected
// proposal is undone and does not advance it), `lastLargeStep_` is the iteration of the last accepted
// large step.
//
// Lazy mutation. A proposal conceptually mutates every coordinate of the infinite vector. Only the ones
// the path evaluator reads are touched, when they are read:
//   - large step: the coordinate is redrawn uniformly;
//   - small step: if it was last modified before the last accepted large step it is first redrawn
//     uniformly (that large step redrew it); then the n = iteration - modify pending small steps are
//     applied at once: n exponential steps in sequence, or one Gaussian step of sigma * sqrt(n) (the sum
//     of n independent N(0, sigma^2) is N(0, n sigma^2); wrapping to [0,1) commutes with summation).
// A coordinate that has never been read: during the replay of the start state (iteration 0) it takes
// the bootstrap candidate's value IndependentSource::candidate(jobSeed, candidate).valueAt(s, j); afterwards it is
// a fresh uniform from the chain's own generator (the start state's unread coordinates are independent
// uniforms, and uniform + any mutation mod 1 is uniform, so no pending steps need applying).
//
// accept() commits. reject() restores every coordinate touched by the proposal exactly (value, time
// stamp, and "never read") from a touched list: O(touched), no allocation once the vectors have grown.
//
// Randomness. Mutation decisions, mutation offsets and fresh coordinates come from a Pcg32 seeded from
// (job seed, chain index) only, never from the start candidate: two chains that start from the same
// candidate follow different trajectories.
#pragma once
#include <cstdint>
#include <vector>

#include "common/core/rng.h"
#include "common/core/vec.h"
#include "common/sampler/sample_source.h"

namespace mlt {

enum class SmallStepKernel { Kelemen, Gaussian };

struct KelemenParams {
  float largeStepProb = 0.3f;
  SmallStepKernel kernel = SmallStepKernel::Kelemen;
  float s1 = 1.0f / 1024, s2 = 1.0f / 64;  // exponential kernel: |dv| = s2 * exp(-log(s2/s1) * u)
  float sigma = 0.01f;                     // Gaussian kernel
};

// Mutation types the chain loop reports statistics for.
enum class MutationType : int { Large = 0, Small = 1 };

// The chain's random stream for (job seed, chain index); `purpose` separates independent streams
// (0: sample source mutations, 1: acceptance decisions).
Pcg32 chainRng(uint64_t jobSeed, uint64_t chainIndex, uint64_t purpose);

class KelemenSource final : public SampleSource {
 public:
  KelemenSource(const KelemenParams& params, uint64_t jobSeed, uint64_t chainIndex, uint64_t startCandidate);

  // ---- chain protocol -------------------------------------------------------------------------
  // Iteration 0 (after construction) replays the start candidate: evaluate once, then call accept().
  // startIteration() begins a proposal: decides large or small step.
  MutationType startIteration();
  // Force the next proposal's type (tests; a chain loop that chooses the type itself).
  void startIteration(MutationType type);
  void accept();
  void reject();
  bool largeStep() const { return largeStep_; }
  int64_t iteration() const { return iteration_; }

  // ---- SampleSource -----------------------------------------------------------------------------
  void startStream(Stream s) override { stream_ = static_cast<int>(s); next_ = 0; }
  void seek(int index) override { next_ = index; }
  float next1D() override;  // = read(stream_, next_++), with read's body inlined
  Vec2 next2D() override;   // the same two reads in one call (most of a path's reads come in pairs)

  // Current value of a coordinate (applies pending mutations, exactly like next1D()).
  float read(int stream, int index);
  // The camera's film position numbers Camera[0,1] of the current proposal, read(): a large step's are
  // drawn now if its target did not read them. The stratum point of a primary-sample chain's large step
  // (chain.h, ChainState::stratumPoint).
  Vec2 filmPositionNumbers() { return {read(int(Stream::Camera), 0), read(int(Stream::Camera), 1)}; }
  // Reversible jumps (Bitterli et al. 2017): sets a coordinate in the current iteration, recorded on the
  // touched list like a read so that reject() restores it exactly. A jump's iteration (started as a
  // small step) writes every coordinate its target reads, so none of them is lazily mutated.
  void write(int stream, int index, float value);
  // The committed vector of one stream as stored (for tests: no pending mutations are applied).
  std::vector<float> storedValues(int stream) const;
  const KelemenParams& params() const { return params_; }
  uint64_t jobSeed() const { return jobSeed_; }
  uint64_t chainIndex() const { return chainIndex_; }

  // Small-step kernel applied n times to v (n >= 1), exposed for tests of lazy == eager.
  float mutate(float v, int64_t n);

 private:
  static constexpr int64_t kNeverRead = -1;
  struct Coord {
    float value = 0;
    float backupValue = 0;
    int64_t modify = kNeverRead;
    int64_t backupModify = kNeverRead;
  };
  struct Touched { int stream, index; };

  float readImpl(int stream, int index);
  float readFast(int stream, int index);
  float readSlow(int stream, int index);
  Coord& grow(int stream, int index);
  float firstRead(int stream, int index);
  float step(float v, uint32_t bits) const;  // one exponential-kernel step, offset from 32 random bits

  KelemenParams params_;
  uint64_t jobSeed_ = 0, chainIndex_ = 0;
  IndependentSource candidate_;
  Pcg32 rng_;
  std::vector<Coord> coords_[kNumStreams];
  std::vector<Touched> touched_;  // the first nTouched_ entries (grown, never shrunk)
  size_t nTouched_ = 0;
  int64_t iteration_ = 0, lastLargeStep_ = 0;
  bool largeStep_ = false;
  int stream_ = 0, next_ = 0;
  float logRatio_;          // log(s2 / s1)
  // Exponential kernel: |dv|(u) = s2 exp(-log(s2/s1) u) tabulated at u = i / kStepTable, linearly
  // interpolated (relative error < 1e-6; the kernel stays symmetric, so the chain stays exact).
  static constexpr int kStepTable = 1024;
  float stepTable_[kStepTable + 1];
  float stepDiff_[kStepTable];  // stepTable_[i + 1] - stepTable_[i] (the same float the lerp computed)
  bool singleStepInline_;       // exponential kernel and uniformAfter_ > 1: n = 1 is one step()
  int64_t uniformAfter_;    // exponential kernel: after this many steps the offset is uniform to 2^-30
};

// ---- Reversible jumps and path-space chains ---------------------------------------------------------
// Reversible-jump MLT (common/methods/rjmlt/) writes a path's inverted numbers with write() and supplies
// its own T-ratio * |Jacobian| to the chain loop (chain.h: Proposal::tRatio). Veach's path-space MLT keeps
// a path, not numbers: its state implements ChainState (chain.h) directly.

}  // namespace mlt
