// exr_pixels A.exr [B.exr]: prints an EXR's size, the SHA-256 of its pixels (the float bytes r, g, b per
// pixel, row-major, as tests/golden_images_test.cpp hashes them) and its metadata keys; given two files,
// exits 0 only if their pixels are bit-identical (the metadata may differ: a farm job id, a wall time);
// if they differ, it prints A's relMSE and brightness error against B as the evaluation harness computes them.
// Used by tests/bench/farm_overhead.sh to check that the farm and --in-process rendered the same image.
// Given one file, it also prints the image's mean r, g, b and luminance and every numeric metadata value
// (b, bStdErr, bBootstrap, ...): how a brightness question is answered without a Python EXR module.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>
#include <vector>

#include "common/core/sha256.h"
#include "common/io/exr_io.h"
#include "tools/eval/metrics.h"

namespace {

std::string pixelDigest(const mlt::ExrImage& img) {
  mlt::Sha256 sha;
  for (const mlt::Color& c : img.rgb) {
    const float v[3] = {c.r, c.g, c.b};
    sha.update(v, sizeof v);
  }
  return sha.hexDigest();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: exr_pixels A.exr [B.exr]\n");
    return 2;
  }
  try {
    std::vector<mlt::ExrImage> images;
    std::string digests[2];
    for (int i = 1; i < argc; ++i) {
      images.push_back(mlt::readExr(argv[i]));
      const mlt::ExrImage& img = images.back();
      digests[i - 1] = pixelDigest(img);
      std::printf("%s: %dx%d pixels sha256 %s, %zu metadata keys\n", argv[i], img.width, img.height,
                  digests[i - 1].c_str(), img.metadata.numbers.size() + img.metadata.strings.size());
    }
    if (argc == 2) {
      const mlt::ExrImage& img = images[0];
      double sum[3] = {0, 0, 0};
      for (const mlt::Color& c : img.rgb) {
        sum[0] += c.r;
        sum[1] += c.g;
        sum[2] += c.b;
      }
      const double n = img.rgb.empty() ? 1.0 : double(img.rgb.size());
      const double r = sum[0] / n, g = sum[1] / n, b = sum[2] / n;
      std::printf("mean r %.9g g %.9g b %.9g luminance %.9g\n", r, g, b,
                  0.212671 * r + 0.715160 * g + 0.072169 * b);
      for (const auto& [key, value] : img.metadata.numbers) std::printf("  %s = %.9g\n", key.c_str(), value);
    }
    if (argc == 3) {
      const bool same = digests[0] == digests[1];
      std::printf("pixels %s\n", same ? "identical" : "DIFFER");
      const mlt::ExrImage &a = images[0], &r = images[1];
      if (!same && a.rgb.size() == r.rgb.size() && !a.rgb.empty()) {
        // The evaluation harness's metrics, B taken as the reference.
        const mlt::eval::ImageMetrics m = mlt::eval::computeMetrics(a.rgb, r.rgb, 0.01);
        // Where the error is: the three pixels holding the most of it.
        const std::vector<float> e = mlt::eval::relativeErrorMap(a.rgb, r.rgb, 0.01);
        std::vector<size_t> order(e.size());
        for (size_t i = 0; i < order.size(); ++i) order[i] = i;
        const size_t top = std::min<size_t>(3, order.size());
        std::partial_sort(order.begin(), order.begin() + top, order.end(), [&](size_t x, size_t y) { return e[x] > e[y]; });
        double total = 0;
        for (double v : e) total += v;
        // And the share in the pixels brighter than 20x the reference's mean (a light seen directly).
        double refMean = 0, bright = 0;
        for (const mlt::Color& c : r.rgb) refMean += double(mlt::luminance(c)) / double(r.rgb.size());
        size_t brightPixels = 0;
        for (size_t i = 0; i < e.size(); ++i)
          if (mlt::luminance(r.rgb[i]) > 20 * refMean) bright += e[i], ++brightPixels;
        std::printf("pixels brighter than 20x the mean: %zu, %.1f%% of the error\n", brightPixels,
                    total > 0 ? 100 * bright / total : 0.0);
        for (size_t j = 0; j < top; ++j) {
          const size_t i = order[j];
          std::printf("pixel (%zu, %zu): %.1f%% of the error, luminance %.4g against %.4g\n", i % size_t(a.width),
                      i / size_t(a.width), total > 0 ? 100 * e[i] / total : 0.0, mlt::luminance(a.rgb[i]), mlt::luminance(r.rgb[i]));
        }
        std::printf("relMSE %.6g brightness %+.4f%%\n", m.relMSE, 100 * m.meanErr);
      }
      return same ? 0 : 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "exr_pixels: %s\n", e.what());
    return 2;
  }
}
