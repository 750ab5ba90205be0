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
  const double scaled = std::ldexp(v, kQuantumExp);
  // |v| >= 2^(52 - kQuantumExp): the spacing of doubles there is already >= 2^-kQuantumExp, so v is a
  // multiple of the quantum as it stands. Keep it: a firefly must never fail a render.
  if (!(std::fabs(scaled) < 0x1p52)) return v;
  const double lo = std::floor(scaled);
  const double u = double(mix64(key) >> 11) * 0x1p-53;
  return std::ldexp(u < scaled - lo ? lo + 1 : lo, -kQuantumExp);
}
}  // namespace

void quantizeSums(TargetSums& sums, uint64_t jobSeed, uint64_t unitIndex, uint64_t slot) {
  const uint64_t k = hashKeys(hashKeys(jobSeed, unitIndex, 0x6273756dULL), slot, 0);
  sums.sum = quantize(sums.sum, k + 1);
  sums.sumSq = quantize(sums.sumSq, k + 2);
}

void quantizeFilm(Film& film, uint64_t jobSeed, uint64_t unitIndex) {
  const uint64_t base = hashKeys(jobSeed, unitIndex, 0x71756e74ULL);
  // Zero entries (most of a chain's film) stay zero and cost no hashing.
  auto quantizeBuffer = [base](std::vector<RGBd>& buffer, uint64_t which) {
    for (size_t i = 0; i < buffer.size(); ++i) {
      RGBd& v = buffer[i];
      if (v.r == 0 && v.g == 0 && v.b == 0) continue;
      const uint64_t k = hashKeys(base, i, which);
      v.r = quantize(v.r, k + 1);
      v.g = quantize(v.g, k + 2);
      v.b = quantize(v.b, k + 3);
    }
  };
  quantizeBuffer(film.splatSums(), 0);
  quantizeBuffer(film.pixelSums(), 1);
  for (size_t l = 1; l < film.splatLayerCount(); ++l)
    if (film.hasSplatLayer(l)) quantizeBuffer(film.splatLayer(l), l + 1);
}

}  // namespace mlt
