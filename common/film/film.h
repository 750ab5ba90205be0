// The film: raw sums in double, normalized only when developed, so that partial films merge exactly.
//
// Two kinds of buffer, both with a box reconstruction filter of one pixel (each sample lands in one pixel):
//  - pixel estimates: sum of sample values and the number of samples per pixel (camera-driven samples,
//    pt and bdpt's t>=2 strategies). Developed as sum / count.
//  - splats: sum of splatted values anywhere on the film (light tracing, bdpt's t=1, every MLT splat).
//    Developed as splatSum * splatScale, where the caller supplies the scale:
//      light tracing / bdpt t=1 with N light paths over P pixels:  P / N     (camera We is normalized
//        over the whole film, see interfaces/camera.h)
//      Markov chains:                                               b * P / M (M = total mutations;
//        derivation in mlt/develop.h)
//    There is one splat buffer per estimator *component* (a "layer"), each developed with its own scale:
//    layer 0 is splatSums() (light tracing, bdpt's t = 1, a Markov chain job's direct pass); a Markov
//    chain job splats path length slot l into layer 1 + 2 l (mlt/develop.h: chainLayer; layer 2 + 2 l holds
//    b's strata of that length), so that b_k, known only once every chain has
//    reported its large steps, is applied when the image is developed and never inside a chain. Layers
//    other than 0 are allocated on first use (a chain's partial film holds only its own).
// Accumulation order matters for bit-identical results: merge() adds another film element-wise, and
// callers merge in a fixed order (chain index) to make the sums independent of scheduling.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/film/pixel_buffer.h"

namespace mlt {

struct RGBd {
  double r = 0, g = 0, b = 0;
  void add(const Color& c) { r += c.r; g += c.g; b += c.b; }
  RGBd& operator+=(const RGBd& o) { r += o.r; g += o.g; b += o.b; return *this; }
};
// A film buffer: pages of pixels nothing writes stay unallocated (pixel_buffer.h).
using PixelBuffer = ZeroedBuffer<RGBd>;

// Index of the pixel containing pRaster (pixels) on a width x height film, row-major from the top-left,
// or -1 when it lies off the film or is not a number.
inline long filmPixelIndex(Vec2 pRaster, int width, int height) {
  const float fx = std::floor(pRaster.x), fy = std::floor(pRaster.y);
  // Written so that NaN coordinates fail the test too.
  if (!(fx >= 0.f && fy >= 0.f && fx < float(width) && fy < float(height))) return -1;
  const int x = static_cast<int>(fx), y = static_cast<int>(fy);
  if (x >= width || y >= height) return -1;  // guard against float rounding at the far edge
  return long(y) * width + x;
}

class Film {
 public:
  Film() = default;
  Film(int width, int height);
  int width() const { return width_; }
  int height() const { return height_; }
  size_t pixelCount() const { return size_t(width_) * size_t(height_); }

  // A camera sample for the pixel containing pRaster (pixels). Non-finite values are counted and dropped.
  void addSample(Vec2 pRaster, const Color& L);
  // A splat anywhere on the film, into splat layer `layer`. Non-finite values are counted and dropped;
  // off-film splats are ignored.
  void addSplat(Vec2 pRaster, const Color& v, size_t layer = 0);
  // Element-wise sum of every buffer (layers missing on one side count as zero); sizes must match
  // (throws std::invalid_argument otherwise).
  void merge(const Film& other);

  // Developed linear RGB, row-major from the top-left: pixel sum / count + sum over layers l of
  // layerScales[l] * splat layer l. Throws std::invalid_argument if an allocated layer has no scale.
  std::vector<Color> develop(const std::vector<double>& layerScales) const;
  std::vector<Color> develop(double splatScale) const { return develop(std::vector<double>{splatScale}); }

  // Splat layers: layers [0, splatLayerCount()) exist as slots; hasSplatLayer tells which hold a buffer.
  size_t splatLayerCount() const { return splat_.size(); }
  bool hasSplatLayer(size_t layer) const { return layer < splat_.size() && !splat_[layer].empty(); }
  std::vector<uint32_t> splatLayers() const;  // the layers that hold a buffer, ascending (0 always first)
  PixelBuffer& splatLayer(size_t layer);  // allocates a zero layer if absent
  const PixelBuffer& splatLayer(size_t layer) const;  // throws std::out_of_range if absent

  // Raw access (for I/O and the wire).
  PixelBuffer& pixelSums() { return pixelSum_; }
  std::vector<double>& pixelCounts() { return pixelCount_; }
  PixelBuffer& splatSums() { return splat_[0]; }
  const PixelBuffer& pixelSums() const { return pixelSum_; }
  const std::vector<double>& pixelCounts() const { return pixelCount_; }
  const PixelBuffer& splatSums() const { return splat_[0]; }
  uint64_t nonFiniteSamples() const { return nonFinite_; }
  void setNonFiniteSamples(uint64_t n) { nonFinite_ = n; }

 private:
  int width_ = 0, height_ = 0;
  PixelBuffer pixelSum_;
  std::vector<double> pixelCount_;
  std::vector<PixelBuffer> splat_ = std::vector<PixelBuffer>(1);  // [0] allocated by the constructor
  uint64_t nonFinite_ = 0;
};

}  // namespace mlt
