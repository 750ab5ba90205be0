// Batches of independent pixel samples through a path evaluator: the methods pt, lt and bdpt
// (common/methods/sample_method.h) and the direct pass of a chain job with separateDirect.
//
// Sample indexing (the same however the work is split or scheduled): sample k of pixel (x, y) reads the
// primary samples IndependentSource(hashKeys(seed, y * width + x), k). A work unit holds samples
// [sampleBegin, sampleEnd) of every pixel. For lt the pixel loop only defines that indexing: one light
// path per (pixel, sample), all of its splats go to the splat buffer.
//
// Exact merging: each unit's pixel and splat sums are rounded to multiples of 2^-kQuantumExp (unbiased
// stochastic rounding keyed by (job seed, unit, element); quantizeFilm in common/mlt/develop.h, the same
// as the Markov chains), and pixel counts are integers. Sums of such values are exact in double, so any
// grouping of units (one by one in-process, contiguous tasks on the farm) develops to identical bytes.
// Bound: grouping-independent bytes hold while the merged per-pixel sums stay below 2^(53 -
// kQuantumExp) = 2^27 ~ 1.3e8 (a unit's own sum of 2^26 or more is already a multiple of the quantum and
// is kept as it is, so a firefly never fails a unit) (i.e. spp * mean pixel value, splats in the same units); beyond that the
// image is still right but its last bits may depend on the grouping. The rounding error is at most
// 2^-26 ~ 1.5e-8 per unit and pixel before the division by the sample count.
#pragma once
#include <vector>

#include "common/job/job_types.h"

namespace mlt {

class PathEvaluator;

// Units of samplesPerUnit spp each (the last one may be shorter). samplesPerUnit = 0 picks
// ceil(spp / kAutoSampleUnits): a split that depends on spp only, never on the thread or worker count,
// because the split decides the order of floating-point additions and so the image's bits.
constexpr int kAutoSampleUnits = 16;
JobPlan planSampleJob(const RenderSettings& settings);
// One unit: the plan's samples [unit.sampleBegin, unit.sampleEnd) of every pixel through `evaluator`
// (the method's: pt, lt, bdpt, or the pt direct pass of a chain job).
PartialResult runSampleUnit(const PathEvaluator& evaluator, const JobPlan& plan, const WorkUnit& unit);
// bdpt only: one film per technique (s, t) with path length L = s + t - 1 in [1, maxLength] (longer
// paths are left out), for inspecting strategies. Each film holds that technique's MIS-weighted
// contributions: t >= 2 as pixel estimates (every camera sample counted, zeros included, so the
// technique images sum to the full image), t = 1 as splats; develop each with the same P / N.
struct TechniqueFilms {
  int maxLength = 0;
  std::vector<Film> films;  // index(s, t)
  TechniqueFilms() = default;
  TechniqueFilms(int maxLength, int width, int height);
  static int index(int s, int t) { const int L = s + t - 1; return (L - 1) * (L + 2) / 2 + s; }
  static int count(int maxLength) { return index(0, maxLength + 2); }  // first index of length maxLength+1
};
// Where a camera sample lies in its pixel (PixelSampling::points):
//  - Sobol (the default, also without a PixelSampling): pixel j's sample i lies at sobolPixelPoint(its key,
//    i). Any prefix of a pixel's samples covers it evenly, so a time budget's pt and bdpt and the chain
//    methods' direct pass get stratified pixels whatever count they stop at.
//  - Hammersley: pixel j's sample i of n lies at stratifiedPixelPoint(its key, i, n), the rotated
//    Hammersley points of a known n: the pass of the lights seen directly (DirectLight::Emission), where a
//    light a pixel wide is an outline in every pixel it touches, and a pixel it covers by a sliver is worth
//    ~nothing in the reference but a whole sample's radiance / n where one of n samples hits it.
//  - Hashed: the camera's own hashed numbers (independent points; what every sample used before the Sobol
//    points; kept for tests that compare with it).
// Each point is uniform on the pixel, so a pixel's mean of any set of its samples stays unbiased; the
// stratified ones cover it evenly (the variance at an outline falls as ~n^-1.5 instead of n^-1). Light
// tracing (lt) takes no camera sample and ignores this.
//  - multiplicity (per pixel, row-major; empty: 1 everywhere): m_j samples per sample index k, numbered
//    i = k m_j + r (r < m_j) of n = spp m_j; the pixel's mean is its sum over its count, as always.
struct PixelSampling {
  enum class Points { Sobol, Hammersley, Hashed };
  Points points = Points::Sobol;
  std::vector<uint8_t> multiplicity;
};
PartialResult runSampleUnit(const PathEvaluator& evaluator, const JobPlan& plan, const WorkUnit& unit,
                            TechniqueFilms* techniques, const PixelSampling* sampling = nullptr);

std::vector<Color> developSampleImage(const JobPlan& plan, const PartialResult& merged);

}  // namespace mlt
