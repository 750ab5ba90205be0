// The primary-sample vector: every random decision a path evaluator makes reads a number in [0,1)
// from a SampleSource. Changing the source changes the method:
//   IndependentSource  - fresh numbers (pt/lt/bdpt, bootstrap candidates), random access by hashing
//   KelemenSource      - a Markov chain over the vector (common/mlt/kelemen_source.h)
//   ReplaySource       - a fixed vector (tests, debugging)
//
// ---- Dimension map (the one place it is documented) -------------------------------------------
// Coordinates live in separate streams so that a change of path length does not change the meaning of
// other coordinates (Hachisuka et al. 2014, sec. 4; pbrt-v3 MLTSampler):
//   Stream::Camera  : [0,1] raster position on the film (in [0,1)^2, scaled by the film size)
//                     [2,3] lens position
//                     then per camera-subpath bounce i (i = 0, 1, ...): kBsdfDims numbers
//                       [0] component choice, [1,2] direction, [3] Russian roulette
//                       ([0] and [1,2] read only where the vertex's BSDF reads them: Bsdf::reads)
//   Stream::Light   : [0] light choice, [1,2] position on the light, [3,4] emitted direction
//                     then per light-subpath bounce: kBsdfDims numbers as above
//   Stream::Connect : technique-level choices: [0] MMLT's (s,t) technique choice (kConnectTechniqueDim),
//                     then one kNeeDims block per camera-subpath bounce i (i = 0: first surface hit) at
//                     connectNeeOffset(i): [0] light choice, [1,2] point on light. Read by pt's
//                     next-event estimation at bounce i and by bdpt's s=1 light resampling at camera
//                     vertex i+1 (the same strategy, so pt and bdpt share those numbers).
//                     bdpt's t=1 lens sample reuses Camera [2,3] (the lens position of the camera vertex).
// A fixed block size per vertex is what lets a reversible-jump chain rewrite vertex i alone.
// -----------------------------------------------------------------------------------------------
#pragma once
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/core/rng.h"
#include "common/core/vec.h"

namespace mlt {

enum class Stream : int { Camera = 0, Light = 1, Connect = 2 };
constexpr int kNumStreams = 3;
constexpr int kCameraDims = 4;  // raster (2) + lens (2)
constexpr int kLightDims = 5;   // choice (1) + position (2) + direction (2)
constexpr int kBsdfDims = 4;    // component (1) + direction (2) + roulette (1)
constexpr int kNeeDims = 3;     // light choice (1) + position (2)
constexpr int kConnectTechniqueDim = 0;  // Connect stream: MMLT technique choice
constexpr int connectNeeOffset(int bounce) { return 1 + bounce * kNeeDims; }

class SampleSource {
 public:
  virtual ~SampleSource() = default;
  // Subsequent next1D() calls read coordinates 0, 1, 2, ... of the given stream.
  virtual void startStream(Stream s) = 0;
  // Jump to coordinate `index` of the current stream (used to read a vertex's fixed block).
  virtual void seek(int index) = 0;
  virtual float next1D() = 0;
  // Two consecutive coordinates, in order (a source may override it to save the second call).
  virtual Vec2 next2D() {
    const float a = next1D();
    return {a, next1D()};
  }
};

// Bootstrap candidates spread their first decisions evenly: the film position (Camera [0,1]), MMLT's
// technique choice (Connect [0]) and the light's choice, position and direction (Light [0..4]) follow
// the Halton sequence in bases 2, 3 | 5 | 7, 11, 13, 17, 19. Candidate i of a path length slot
// (index = slot << kCandidateSlotBits | i) belongs to randomization group g = i mod kCandidateGroups and
// takes point n = i / kCandidateGroups, shifted modulo 1 by a random offset of (seed, slot, g, axis)
// (Cranley-Patterson rotation). Each candidate is still uniform on its own, so every estimate over
// candidates stays unbiased and a chain started from one is exact; but the image's bright and dark
// regions (and the techniques, and the light) are visited in proportion, which removes most of the
// variance of b's estimate (a visible light covering 1% of the film made a uniform c vary by ~6x its
// mean). The groups are independent randomizations of one point set: the spread of their means gives
// b's standard error (common/mlt/bootstrap.cpp).
constexpr int kCandidateSlotBits = 40;
constexpr uint64_t kCandidateGroups = 16;
constexpr int kCandidateAxes = 8;
// Axis a of the candidate's spread coordinates (0, 1: film; 2: technique; 3..7: light).
float candidateCoordinate(uint64_t seed, uint64_t candidate, int axis);
// The axis of (stream, coordinate) for a candidate, or -1 for an ordinary independent coordinate.
constexpr int candidateAxis(int stream, int coordinate) {
  if (stream == 0) return coordinate < 2 ? coordinate : -1;   // Camera: raster position
  if (stream == 2) return coordinate == 0 ? 2 : -1;           // Connect: MMLT's technique
  return coordinate < 5 ? 3 + coordinate : -1;                // Light: choice, position, direction
}

// Fresh uniform numbers. Coordinate j of stream s is hashUniform(seed, index, s, j): a pure function,
// so a bootstrap candidate (seed = job seed, index = candidate index) can be replayed exactly by a
// worker, and coordinates may be read in any order. candidate() makes the bootstrap's sources, whose
// first decisions are candidateCoordinate instead.
class IndependentSource final : public SampleSource {
 public:
  IndependentSource(uint64_t seed, uint64_t index) : seed_(seed), index_(index), hash_(seed, index) {}
  static IndependentSource candidate(uint64_t seed, uint64_t index) {
    IndependentSource s(seed, index);
    s.candidate_ = true;
    return s;
  }
  void reset(uint64_t seed, uint64_t index) {
    seed_ = seed;
    index_ = index;
    hash_ = HashPrefix2(seed, index);
    pixelPoint_ = false;
  }
  // Camera [0,1] (the position in the pixel) read as u instead of hashed numbers, until the next reset
  // (stratifiedPixelPoint: a pixel's samples spread over its area).
  void setPixelPoint(Vec2 u) { pixelPoint_ = true; u_ = u; }
  void startStream(Stream s) override { stream_ = static_cast<int>(s); next_ = 0; }
  void seek(int index) override { next_ = index; }
  float next1D() override {
    ++reads_;
    return valueAt(stream_, next_++);
  }
  Vec2 next2D() override {
    reads_ += 2;
    const float a = valueAt(stream_, next_++);
    return {a, valueAt(stream_, next_++)};
  }
  // Numbers drawn by next1D so far: a deterministic measure of the work of the path that drew them.
  uint32_t reads() const { return reads_; }
  float valueAt(int stream, int coordinate) const {
    if (pixelPoint_ && stream == 0 && coordinate < 2) return coordinate == 0 ? u_.x : u_.y;
    if (candidate_)
      if (const int axis = candidateAxis(stream, coordinate); axis >= 0) return candidateCoordinate(seed_, index_, axis);
    return uniformFromBits(hash_(static_cast<uint64_t>(stream), static_cast<uint64_t>(coordinate)));  // = hashUniform(seed, index, stream, coordinate)
  }

 private:
  uint64_t seed_, index_;
  HashPrefix2 hash_;
  bool candidate_ = false, pixelPoint_ = false;
  Vec2 u_;
  int stream_ = 0, next_ = 0;
  uint32_t reads_ = 0;
};

inline float candidateCoordinate(uint64_t seed, uint64_t candidate, int axis) {
  constexpr uint64_t kBases[kCandidateAxes] = {2, 3, 5, 7, 11, 13, 17, 19};
  const uint64_t slot = candidate >> kCandidateSlotBits;
  const uint64_t i = candidate & ((uint64_t(1) << kCandidateSlotBits) - 1);
  const uint64_t g = i % kCandidateGroups, n = i / kCandidateGroups;
  double h = 0;  // radical inverse of n in the axis' base
  const uint64_t base = kBases[axis];
  double f = 1.0 / double(base);
  for (uint64_t m = n; m > 0; m /= base, f /= double(base)) h += f * double(m % base);
  const double shift = double(hashKeys(seed, slot, g, 0x66696c6dULL, uint64_t(axis)) >> 11) * 0x1p-53;
  double v = h + shift;
  v -= std::floor(v);
  const float out = static_cast<float>(v);
  return out < 1.0f ? out : 0.0f;
}

// The bits of k in reverse order: the radical inverse of k in base 2, times 2^32.
inline uint32_t reversedBits(uint32_t k) {
  uint32_t bits = k;
  bits = (bits << 16) | (bits >> 16);
  bits = ((bits & 0x00ff00ffu) << 8) | ((bits & 0xff00ff00u) >> 8);
  bits = ((bits & 0x0f0f0f0fu) << 4) | ((bits & 0xf0f0f0f0u) >> 4);
  bits = ((bits & 0x33333333u) << 2) | ((bits & 0xccccccccu) >> 2);
  bits = ((bits & 0x55555555u) << 1) | ((bits & 0xaaaaaaaau) >> 1);
  return bits;
}

// Sample k of n of one pixel, spread over the pixel: the Hammersley point ((k + 1/2) / n, radical inverse
// of k in base 2), shifted modulo 1 by a random offset of `key` (Cranley-Patterson rotation). Each point
// is uniform on its own, so a pixel's mean stays unbiased, and the n points cover the pixel evenly: where
// an edge crosses the pixel the mean's variance falls about as n^-1.5 instead of n^-1.
inline Vec2 stratifiedPixelPoint(uint64_t key, uint32_t k, uint32_t n) {
  const uint32_t bits = reversedBits(k);
  const double p[2] = {(double(k) + 0.5) / double(n), double(bits) * 0x1p-32};
  float out[2];
  for (int a = 0; a < 2; ++a) {
    double v = p[a] + double(hashKeys(key, 0x70697870ULL, uint64_t(a)) >> 11) * 0x1p-53;
    v -= std::floor(v);
    out[a] = static_cast<float>(v);
    if (!(out[a] < 1.0f)) out[a] = 0.0f;
  }
  return {out[0], out[1]};
}

// Sample k of one pixel's endless sequence, for renders whose samples per pixel are not known in advance
// (a time budget stops anywhere): the first two dimensions of Sobol's sequence (the radical inverse of k
// in base 2, and the second dimension's generator, the Pascal matrix mod 2), each XORed with a random
// 32-bit mask of `key` (a random digital shift). Each point is uniform on its own (the mask is), so a
// pixel's mean of any set of its samples stays unbiased; the shift keeps the net structure, so every
// prefix of 2^m points is a (0, m, 2)-net (one point in every 2^a x 2^(m-a) box of the pixel) and the
// points a budget stops at cover the pixel evenly: where an edge crosses the pixel the mean's variance
// falls about as n^-1.5 instead of n^-1.
inline Vec2 sobolPixelPoint(uint64_t key, uint32_t k) {
  const uint32_t bits = reversedBits(k);
  // Sobol's second dimension: the XOR of the direction numbers of k's set bits, v_0 = 2^31,
  // v_(b+1) = v_b ^ (v_b >> 1).
  constexpr auto kDirections = [] {
    std::array<uint32_t, 32> v{};
    v[0] = 1u << 31;
    for (size_t b = 1; b < v.size(); ++b) v[b] = v[b - 1] ^ (v[b - 1] >> 1);
    return v;
  }();
  uint32_t second = 0;
  for (uint32_t i = k; i != 0; i &= i - 1) second ^= kDirections[size_t(std::countr_zero(i))];
  const uint32_t x = bits ^ uint32_t(hashKeys(key, 0x736f626cULL, 0) >> 32);
  const uint32_t y = second ^ uint32_t(hashKeys(key, 0x736f626cULL, 1) >> 32);
  return {float(x >> 8) * 0x1p-24f, float(y >> 8) * 0x1p-24f};  // 24 bits: exact in a float, below 1
}

// A fixed vector per stream; reads past the end return `fill`. For tests and for replaying a path.
class ReplaySource final : public SampleSource {
 public:
  explicit ReplaySource(std::vector<std::vector<float>> streams, float fill = 0.5f)
      : streams_(std::move(streams)), fill_(fill) { streams_.resize(kNumStreams); }
  void startStream(Stream s) override { stream_ = static_cast<int>(s); next_ = 0; }
  void seek(int index) override { next_ = index; }
  float next1D() override {
    const auto& v = streams_[stream_];
    const int i = next_++;
    return i < static_cast<int>(v.size()) ? v[i] : fill_;
  }

 private:
  std::vector<std::vector<float>> streams_;
  float fill_;
  int stream_ = 0, next_ = 0;
};

}  // namespace mlt
