#include "common/mlt/develop.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/core/rng.h"

namespace mlt {

double chainSplatScale(double b, uint64_t totalMutations, size_t pixels) {
  return totalMutations > 0 ? b * double(pixels) / double(totalMutations) : 0.0;
}

namespace {
double quantize(double v, uint64_t key) {
  if (v == 0) return 0;
  // Scaling by a power of two is exact (no overflow here: |v| < 2^(52 - kQuantumExp) is tested next, and
  // larger v keeps its value); a multiply, not a call to ldexp.
  constexpr double kQuantum = 1.0 / double(1ull << kQuantumExp);
  const double scaled = v * double(1ull << kQuantumExp);
  // |v| >= 2^(52 - kQuantumExp): the spacing of doubles there is already >= 2^-kQuantumExp, so v is a
  // multiple of the quantum as it stands. Keep it: a firefly must never fail a render.
  if (!(std::fabs(scaled) < 0x1p52)) return v;
  const double lo = std::floor(scaled);
  const double u = double(mix64(key) >> 11) * 0x1p-53;
  return (u < scaled - lo ? lo + 1 : lo) * kQuantum;
}
}  // namespace

void quantizeSums(TargetSums& sums, uint64_t jobSeed, uint64_t unitIndex, uint64_t slot) {
  const uint64_t k = hashKeys(hashKeys(jobSeed, unitIndex, 0x6273756dULL), slot, 0);
  sums.sum = quantize(sums.sum, k + 1);
  sums.sumSq = quantize(sums.sumSq, k + 2);
  sums.bulk = quantize(sums.bulk, k + 3);
  sums.bulkSq = quantize(sums.bulkSq, k + 4);
  sums.excessSq = quantize(sums.excessSq, k + 5);
}

namespace {
// The buffer numbers of the quantization keys: splat layer 0 -> 0, pixel sums -> 1, splat layer l -> l + 1.
uint64_t splatBufferKey(size_t layer) { return layer == 0 ? 0 : layer + 1; }
constexpr uint64_t kPixelSumsKey = 1;

void quantizeValue(RGBd& v, uint64_t base, size_t pixel, uint64_t buffer) {
  const uint64_t k = hashKeys(base, pixel, buffer);
  v.r = quantize(v.r, k + 1);
  v.g = quantize(v.g, k + 2);
  v.b = quantize(v.b, k + 3);
}
uint64_t filmKeyBase(uint64_t jobSeed, uint64_t unitIndex) { return hashKeys(jobSeed, unitIndex, 0x71756e74ULL); }
}  // namespace

void quantizeFilm(Film& film, uint64_t jobSeed, uint64_t unitIndex) {
  const uint64_t base = filmKeyBase(jobSeed, unitIndex);
  // Zero entries (most of a chain's film) stay zero and cost no hashing.
  // Blocks nothing wrote are zero (pixel_buffer.h): not even read.
  auto quantizeBuffer = [base](PixelBuffer& buffer, uint64_t which) {
    for (size_t b = 0; b < buffer.blockCount(); ++b) {
      if (!buffer.blockWritten(b)) continue;
      RGBd* values = buffer.writeBlock(b);
      for (size_t j = 0; j < buffer.blockSize(b); ++j) {
        RGBd& v = values[j];
        if (v.r == 0 && v.g == 0 && v.b == 0) continue;
        quantizeValue(v, base, b * PixelBuffer::kBlock + j, which);
      }
    }
  };
  quantizeBuffer(film.splatSums(), splatBufferKey(0));
  quantizeBuffer(film.pixelSums(), kPixelSumsKey);
  for (size_t l = 1; l < film.splatLayerCount(); ++l)
    if (film.hasSplatLayer(l)) quantizeBuffer(film.splatLayer(l), splatBufferKey(l));
}

void quantizeSplats(SparseSplats& splats, uint64_t jobSeed, uint64_t unitIndex) {
  const uint64_t base = filmKeyBase(jobSeed, unitIndex);
  for (SparseSplats::Layer& l : splats.layers)
    for (size_t j = 0; j < l.index.size(); ++j) {
      RGBd& v = l.value[j];
      if (v.r == 0 && v.g == 0 && v.b == 0) continue;  // as quantizeFilm: a zero sum stays zero
      quantizeValue(v, base, l.index[j], splatBufferKey(l.layer));
    }
}

}  // namespace mlt
