// Checks of an uploaded task result (see result_check.h).
#include "coordinator/result_check.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <fmt/format.h>

#include "common/farm/farm_types.h"
#include "common/job/mlt_job.h"
#include "common/mlt/develop.h"
#include "proto/convert.h"

namespace mlt::farm {
namespace {

using Code = FarmError::Code;

[[noreturn]] void refuse(const std::string& field, const std::string& what) {
  throw FarmError(Code::InvalidArgument, fmt::format("{}: {}", field, what));
}

void checkBuffer(std::span<const RGBd> values, const std::string& field, int width) {
  static_assert(sizeof(RGBd) == 3 * sizeof(double));
  // Most of a task's film is zero (a chain visits a fraction of the pixels of each length); onQuantumGrid
  // reads each value's bits and settles a zero at its first test. Names the first pixel that fails.
  const double* d = &values.data()->r;
  const size_t n = 3 * values.size();
  for (size_t k = 0; k < n; ++k) {
    if (!onQuantumGrid(d[k])) {
      const size_t i = k / 3;
      refuse(field, fmt::format("pixel ({}, {}) holds {}: every sum must be finite and a multiple of 2^-{}",
                                i % size_t(width), i / size_t(width), d[k], kQuantumExp));
    }
  }
}

// b's strata (develop.h (D6), film layer bStrataLayer(slot) = 2 + 2 slot): per pixel a whole count of
// large steps, a sum of m = min(c, tau) >= 0 and of m^2 >= 0, and one count per large step of the slot
// (ChainStats::largeStepSums). A layer that disagrees with the large steps would be set aside by refinedB
// without a word; here it is refused, naming the layer.
void checkStrata(const PartialResult& r, int width, uint32_t maxLayer) {
  for (size_t slot = 0; bStrataLayer(slot) <= maxLayer; ++slot) {
    const size_t l = bStrataLayer(slot);
    if (!r.film.hasSplatLayer(l)) continue;
    const std::string field = fmt::format("partial.splat_layers[{}]", l);
    const PixelBuffer& layer = r.film.splatLayer(l);
    double n = 0;  // whole numbers below 2^53: exact
    for (size_t i = 0; i < layer.size(); ++i) {
      const RGBd& v = layer[i];
      if (!(v.r >= 0 && v.r == std::floor(v.r) && v.g >= 0 && v.b >= 0))
        refuse(field, fmt::format("pixel ({}, {}) holds ({}, {}, {}): b's strata hold a whole count of large steps and "
                                  "sums of m >= 0 and m^2 >= 0", i % size_t(width), i / size_t(width), v.r, v.g, v.b));
      n += v.r;
    }
    const uint64_t large = slot < r.stats.largeStepSums.size() ? r.stats.largeStepSums[slot].n : 0;
    if (n != double(large))
      refuse(field, fmt::format("b's strata of path length slot {} count {} large steps, but "
                                "partial.stats.large_step_sums[{}].n is {}", slot, n, slot, large));
  }
}

}  // namespace

namespace {
// The path length slots whose chain and strata layers a job may fill.
size_t chainSlots(const JobPlan& plan) {
  return std::max<size_t>({1, plan.norm.mutationsPerLength.size(),
                           plan.settings.integrator.maxDepth >= 0 ? size_t(plan.settings.integrator.maxDepth) + 1 : 0});
}
}  // namespace

uint32_t maxSplatLayer(const JobPlan& plan) {
  size_t maxLayer = maxChainFilmLayer(chainSlots(plan));
  const size_t planned = plan.norm.mutationsPerLength.size();  // Kelemen MIS: the large steps' layers (D7)
  if (plan.settings.splatting == MltSplatting::KelemenMIS && planned > 0)
    maxLayer = std::max(maxLayer, largeStepLayer(planned - 1, planned));
  return uint32_t(std::min<size_t>(wire::kMaxSplatLayer, maxLayer));
}

void checkTaskResult(const JobPlan& plan, uint32_t task, TaskRange range, const PartialResult& r) {
  const int w = plan.settings.width, h = plan.settings.height;
  if (r.film.width() != w || r.film.height() != h)
    refuse("partial.width/height", fmt::format("{}x{}, the job renders {}x{}", r.film.width(), r.film.height(), w, h));
  std::vector<uint32_t> expect;
  for (uint32_t u = range.begin; u < range.end; ++u) expect.push_back(u);
  if (r.units != expect)
    refuse("partial.units", fmt::format("task {} must hold units {}-{}", task, range.begin, range.end - 1));
  uint64_t samples = 0, pixelSamples = 0;  // mutations or pixel samples; pixel samples a pixel takes at most
  for (uint32_t u = range.begin; u < range.end; ++u) {
    const WorkUnit& unit = plan.units[u];
    samples += unitWork(plan, unit);
    if (unit.sampleEnd > unit.sampleBegin)  // the pass of the lights seen directly takes more in some pixels
      pixelSamples += uint64_t(unit.sampleEnd - unit.sampleBegin) * uint64_t(directPassMultiplicity(plan.settings));
  }
  if (r.samples != samples)
    refuse("partial.samples", fmt::format("{}, but units {}-{} make {}", r.samples, range.begin, range.end - 1, samples));
  if (r.film.nonFiniteSamples() > samples + pixelSamples * r.film.pixelCount())
    refuse("partial.non_finite", fmt::format("{} of {} samples", r.film.nonFiniteSamples(), samples));
  const uint32_t maxLayer = maxSplatLayer(plan);
  for (uint32_t l : r.film.splatLayers())
    if (l > maxLayer) refuse("partial.splat_layers", fmt::format("layer {} (this job fills layers 0-{})", l, maxLayer));
  // Pixel counts: whole samples, at most the pixel samples the units take.
  const std::vector<double>& counts = r.film.pixelCounts();
  for (size_t i = 0; i < counts.size(); ++i)
    if (!(counts[i] >= 0 && counts[i] <= double(pixelSamples) && counts[i] == std::floor(counts[i])))
      refuse("partial.pixel_counts", fmt::format("pixel ({}, {}) counts {} samples (whole numbers 0-{})", i % size_t(w),
                                                 i / size_t(w), counts[i], pixelSamples));
  checkBuffer(r.film.pixelSums(), "partial.pixel_sums", w);
  for (uint32_t l : r.film.splatLayers()) checkBuffer(r.film.splatLayer(l), fmt::format("partial.splat_layers[{}]", l), w);
  checkStrata(r, w, uint32_t(std::min<size_t>(maxLayer, maxChainFilmLayer(chainSlots(plan)))));  // not (D7)'s
}

}  // namespace mlt::farm
