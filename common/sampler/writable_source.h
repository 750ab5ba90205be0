// WritableSource: a primary-sample vector that can be read and written coordinate by coordinate, for
// reversible-jump MLT (Bitterli et al. 2017): a path turned back into numbers is written into the fixed
// per-vertex blocks of the dimension map (sample_source.h), so "rewrite vertex i" is a local operation.
// Coordinates never written read as independent uniforms of (seed, stream, index) (like IndependentSource),
// so the vector is a pure function of its seed and the writes. The Markov chain's version is
// KelemenSource::write (common/mlt/kelemen_source.h), which records writes for reject().
#pragma once
#include <cstdint>
#include <vector>

#include "common/core/rng.h"
#include "common/sampler/sample_source.h"

namespace mlt {

class WritableSource final : public SampleSource {
 public:
  explicit WritableSource(uint64_t seed) : seed_(seed) {}
  void startStream(Stream s) override { stream_ = static_cast<int>(s); next_ = 0; }
  void seek(int index) override { next_ = index; }
  float next1D() override { return read(stream_, next_++); }

  float read(int stream, int index) const {
    const auto& v = values_[stream];
    if (index < static_cast<int>(v.size()) && written_[stream][index]) return v[index];
    return hashUniform(seed_, 0x77726974ULL, static_cast<uint64_t>(stream), static_cast<uint64_t>(index));
  }
  void write(int stream, int index, float value) {
    if (index >= static_cast<int>(values_[stream].size())) {
      values_[stream].resize(index + 1, 0.0f);
      written_[stream].resize(index + 1, 0);
    }
    values_[stream][index] = value;
    written_[stream][index] = 1;
  }

 private:
  uint64_t seed_;
  std::vector<float> values_[kNumStreams];
  std::vector<uint8_t> written_[kNumStreams];
  int stream_ = 0, next_ = 0;
};

}  // namespace mlt
