// Monte Carlo estimates of image statistics from a PathEvaluator, with standard errors, for tests that
// compare integrators or check analytic values.
//
// Samples come in batches of P = width * height: sample i uses IndependentSource(seed, i) and pixel
// i mod P (stratified: each batch visits every pixel once), and its splats are binned by raster position.
// With We normalized over the film (interfaces/camera.h), the mean over a batch of the sum of each sample's
// splats is an unbiased estimate of the image mean, whatever mix of camera-side (t >= 2) and light-side
// (t = 1) splats they hold; restricted to a tile and times the number of tiles it estimates the tile
// mean. Batches are independent: the standard error is the spread of the batch means / sqrt(batches).
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "common/integrators/path_evaluator.h"

namespace mlt::test {

struct ImageStats {
  int tilesX = 0, tilesY = 0;
  uint64_t n = 0;
  std::vector<double> mean, stdErr;  // [0] image mean, [1 + ty * tilesX + tx] tile means
  int size() const { return int(mean.size()); }
};

// Value of a splat: a scalar per colour (channel 0..2) or luminance (channel -1).
// filter: keep a splat (e.g. one (s,t) technique); nullptr keeps all.
ImageStats estimateImage(const PathEvaluator& evaluator, int width, int height, uint64_t seed, uint64_t n,
                         int tilesX, int tilesY, int channel = -1,
                         const std::function<bool(const Splat&)>& filter = nullptr);

// Generic form: sample(i, out) fills the splats of sample i (out is cleared before); batches of `batch`
// consecutive samples (n rounded up to whole batches, at least two).
ImageStats estimateImageFrom(const std::function<void(uint64_t, PathContribution&)>& sample, int width, int height,
                             uint64_t n, int tilesX, int tilesY, int channel, uint64_t batch);

// Largest |a - b| / sqrt(seA^2 + seB^2) over all entries (image mean and tiles), and where.
double maxZ(const ImageStats& a, const ImageStats& b, int* where = nullptr);
// |a.mean[0] - value| / a.stdErr[0].
double zImage(const ImageStats& a, double value);

}  // namespace mlt::test
