// Film buffers: box filter of one pixel, raw double sums, development with one scale (see film.h).
#include "common/film/film.h"

#include <cmath>
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
  for (size_t i = 0; i < pixelSum_.size(); ++i) {
    pixelSum_[i] += other.pixelSum_[i];
    pixelCount_[i] += other.pixelCount_[i];
  }
  for (size_t l = 0; l < other.splat_.size(); ++l) {
    if (!other.hasSplatLayer(l)) continue;
    PixelBuffer& mine = splatLayer(l);
    const PixelBuffer& theirs = other.splat_[l];
    for (size_t i = 0; i < mine.size(); ++i) mine[i] += theirs[i];
  }
  nonFinite_ += other.nonFinite_;
}

std::vector<Color> Film::develop(const std::vector<double>& layerScales) const {
  for (size_t l = layerScales.size(); l < splat_.size(); ++l)
    if (hasSplatLayer(l)) throw std::invalid_argument("Film::develop: splat layer " + std::to_string(l) + " has no scale");
  std::vector<Color> out(pixelCount());
  for (size_t i = 0; i < out.size(); ++i) {
    double r = 0, g = 0, b = 0;
    if (pixelCount_[i] > 0) {
      const double inv = 1.0 / pixelCount_[i];
      r = pixelSum_[i].r * inv;
      g = pixelSum_[i].g * inv;
      b = pixelSum_[i].b * inv;
    }
    // Layers in index order, so that the same sums develop to the same floats everywhere.
    for (size_t l = 0; l < splat_.size(); ++l) {
      if (splat_[l].empty()) continue;
      const double scale = layerScales[l];
      r += scale * splat_[l][i].r;
      g += scale * splat_[l][i].g;
      b += scale * splat_[l][i].b;
    }
    out[i] = Color(static_cast<float>(r), static_cast<float>(g), static_cast<float>(b));
  }
  return out;
}

}  // namespace mlt
