// Film buffers: box filter of one pixel, raw double sums, development with one scale (see film.h).
#include "common/film/film.h"

#include <cmath>
#include <utility>
#include <stdexcept>
#include <string>

namespace mlt {

Film::Film(int width, int height) : width_(width), height_(height) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("Film: size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  pixelSum_ = PixelBuffer(pixelCount());
  pixelCount_.assign(pixelCount(), 0.0);
  splat_[0] = PixelBuffer(pixelCount());
}

PixelBuffer& Film::splatLayer(size_t layer) {
  if (layer >= splat_.size()) splat_.resize(layer + 1);
  if (splat_[layer].empty()) splat_[layer] = PixelBuffer(pixelCount());
  return splat_[layer];
}

std::vector<uint32_t> Film::splatLayers() const {
  std::vector<uint32_t> layers = {0};
  for (size_t l = 1; l < splat_.size(); ++l)
    if (hasSplatLayer(l)) layers.push_back(uint32_t(l));
  return layers;
}

const PixelBuffer& Film::splatLayer(size_t layer) const {
  if (!hasSplatLayer(layer)) throw std::out_of_range("Film: no splat layer " + std::to_string(layer));
  return splat_[layer];
}

void Film::addSample(Vec2 pRaster, const Color& L) {
  if (!L.isFinite()) {
    ++nonFinite_;
    return;
  }
  const long i = filmPixelIndex(pRaster, width_, height_);
  if (i < 0) return;
  pixelSum_[i].add(L);
  pixelCount_[i] += 1.0;
}

void Film::addSplat(Vec2 pRaster, const Color& v, size_t layer) {
  if (!v.isFinite()) {
    ++nonFinite_;
    return;
  }
  const long i = filmPixelIndex(pRaster, width_, height_);
  if (i < 0) return;
  PixelBuffer& buffer = layer == 0 ? splat_[0] : splatLayer(layer);
  buffer[i].add(v);
}

void Film::merge(const Film& other) {
  if (other.width_ != width_ || other.height_ != height_)
    throw std::invalid_argument("Film::merge: size mismatch " + std::to_string(width_) + "x" +
                                std::to_string(height_) + " vs " + std::to_string(other.width_) + "x" +
                                std::to_string(other.height_));
  // Only the blocks the other film wrote: the rest of it is zero (pixel_buffer.h).
  for (size_t i = 0; i < pixelSum_.size(); ++i) pixelCount_[i] += other.pixelCount_[i];
  other.pixelSum_.forEachWrittenBlock([&](size_t b, const RGBd* theirs, size_t n) {
    RGBd* mine = pixelSum_.writeBlock(b);
    for (size_t i = 0; i < n; ++i) mine[i] += theirs[i];
  });
  for (size_t l = 0; l < other.splat_.size(); ++l) {
    if (!other.hasSplatLayer(l)) continue;
    PixelBuffer& layer = splatLayer(l);
    other.splat_[l].forEachWrittenBlock([&](size_t b, const RGBd* theirs, size_t n) {
      RGBd* mine = layer.writeBlock(b);
      for (size_t i = 0; i < n; ++i) mine[i] += theirs[i];
    });
  }
  nonFinite_ += other.nonFinite_;
}

std::vector<Color> Film::develop(const std::vector<double>& layerScales) const {
  for (size_t l = layerScales.size(); l < splat_.size(); ++l)
    if (hasSplatLayer(l)) throw std::invalid_argument("Film::develop: splat layer " + std::to_string(l) + " has no scale");
  std::vector<Color> out(pixelCount());
  // Block by block, reading only the layers that wrote the block (pixel_buffer.h): a layer's zeros add
  // nothing, and reading them would fault in pages nothing wrote (60 layers of 50 MB at 1920x1080).
  std::vector<std::pair<const RGBd*, double>> here;  // the block's written layers, in index order
  for (size_t b = 0; b < pixelSum_.blockCount(); ++b) {
    here.clear();
    for (size_t l = 0; l < splat_.size(); ++l)
      if (!splat_[l].empty() && splat_[l].blockWritten(b)) here.emplace_back(splat_[l].block(b), layerScales[l]);
    const bool pixels = pixelSum_.blockWritten(b);
    const size_t i0 = b * PixelBuffer::kBlock, n = pixelSum_.blockSize(b);
    for (size_t j = 0; j < n; ++j) {
      const size_t i = i0 + j;
      double r = 0, g = 0, bl = 0;
      if (pixels && pixelCount_[i] > 0) {
        const double inv = 1.0 / pixelCount_[i];
        r = pixelSum_[i].r * inv;
        g = pixelSum_[i].g * inv;
        bl = pixelSum_[i].b * inv;
      }
      // Layers in index order, so that the same sums develop to the same floats everywhere.
      for (const auto& [values, scale] : here) {
        r += scale * values[j].r;
        g += scale * values[j].g;
        bl += scale * values[j].b;
      }
      out[i] = Color(static_cast<float>(r), static_cast<float>(g), static_cast<float>(bl));
    }
  }
  return out;
}

}  // namespace mlt
