// Random numbers. Two kinds:
//  - Pcg32: a sequential stream (O'Neill's PCG-XSH-RR 64/32), for chains and mutation decisions.
//  - hashUniform(key...): counter-based, random access. The value of coordinate j of stream s of a
//    bootstrap candidate is a pure function of (job seed, candidate index, s, j), so an independent
//    path can be replayed in any order of reads, on any machine.
#pragma once
#include <cstdint>

#include "common/core/vec.h"

namespace mlt {

// SplitMix64 finalizer (Steele et al. 2014): a bijective 64-bit mixer.
inline constexpr uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
// Hash of a tuple of 64-bit keys; order matters. kHashOffset: 2^64 / golden ratio.
inline constexpr uint64_t kHashOffset = 0x9e3779b97f4a7c15ULL;
inline constexpr uint64_t hashKeys(uint64_t a) { return mix64(a + kHashOffset); }
template <typename... Rest>
inline constexpr uint64_t hashKeys(uint64_t a, Rest... rest) {
  return mix64(hashKeys(a) ^ (hashKeys(static_cast<uint64_t>(rest)...) + kHashOffset + (a << 6)));
}
// hashKeys(a, b, c, d) with (a, b) fixed and c, d varying (a source's seed and index; stream, coordinate).
// The fold above is hashKeys(a, b, c, d) = step(a, step(b, step(c, hashKeys(d)))) with
//   step(x, h) = mix64(hashKeys(x) ^ (h + kHashOffset + (x << 6))),
// so what depends on a and b alone is computed once, and hashKeys(x) of small c and d (stream numbers,
// coordinates) comes from a table: 3 mixes per value instead of 7, bit for bit the same
// (tests/mlt_source_test.cpp, IndependentSource.ValuesAreHashUniformBitForBit).
class HashPrefix2 {
 public:
  static constexpr uint64_t kSmall = 64;
  constexpr HashPrefix2(uint64_t a, uint64_t b)
      : ha_(hashKeys(a)), ta_(kHashOffset + (a << 6)), hb_(hashKeys(b)), tb_(kHashOffset + (b << 6)) {}
  constexpr uint64_t operator()(uint64_t c, uint64_t d) const {
    const uint64_t hcd = mix64(small(c) ^ (small(d) + kHashOffset + (c << 6)));
    return mix64(ha_ ^ (mix64(hb_ ^ (hcd + tb_)) + ta_));
  }

 private:
  struct Table {
    uint64_t h[kSmall];
  };
  static constexpr Table kTable = [] {
    Table t{};
    for (uint64_t x = 0; x < kSmall; ++x) t.h[x] = hashKeys(x);
    return t;
  }();
  static constexpr uint64_t small(uint64_t x) { return x < kSmall ? kTable.h[x] : hashKeys(x); }
  uint64_t ha_, ta_, hb_, tb_;
};

// Uniform float in [0, 1) from the top 24 bits of a 64-bit hash.
inline float uniformFromBits(uint64_t bits) { return static_cast<float>(bits >> 40) * 0x1p-24f; }
template <typename... Keys>
inline float hashUniform(Keys... keys) { return uniformFromBits(hashKeys(static_cast<uint64_t>(keys)...)); }

class Pcg32 {
 public:
  Pcg32() { seed(0x853c49e6748fea9bULL, 0xda3e39cb94b95bdbULL); }
  Pcg32(uint64_t seedValue, uint64_t stream) { seed(seedValue, stream); }
  void seed(uint64_t seedValue, uint64_t stream) {
    state_ = 0u;
    inc_ = (stream << 1u) | 1u;
    nextU32();
    state_ += seedValue;
    nextU32();
  }
  uint32_t nextU32() {
    const uint64_t old = state_;
    state_ = old * 0x5851f42d4c957f2dULL + inc_;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
  }
  // Uniform in [0, 1): 24 random bits, exactly representable.
  float uniform() { return static_cast<float>(nextU32() >> 8) * 0x1p-24f; }
  double uniformDouble() {
    const uint64_t hi = nextU32(), lo = nextU32();
    return static_cast<double>(((hi << 32) | lo) >> 11) * 0x1p-53;
  }
  Vec2 uniform2() { const float a = uniform(); return {a, uniform()}; }
  // Uniform integer in [0, n).
  uint32_t bounded(uint32_t n) {
    const uint32_t threshold = (~n + 1u) % n;
    for (;;) {
      const uint32_t r = nextU32();
      if (r >= threshold) return r % n;
    }
  }
  bool operator==(const Pcg32& o) const { return state_ == o.state_ && inc_ == o.inc_; }

 private:
  uint64_t state_, inc_;
};

}  // namespace mlt
