#include "common/bsdf/texture.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_FAILURE_USERMSG
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-but-set-variable"
#include <stb_image.h>
#pragma GCC diagnostic pop

namespace mlt {

float textureAlpha(const Texture& t, Vec2 uv) {
  const float a = luminance(t.eval(uv));
  return std::isfinite(a) ? std::clamp(a, 1e-4f, 4.0f) : 1e-4f;
}

float srgbToLinear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

// ---------------------------------------------------------------------------------------------------
// Checkerboard
// ---------------------------------------------------------------------------------------------------
Color CheckerboardTexture::eval(Vec2 uv) const {
  const float u = scale_.x * uv.x + offset_.x, v = scale_.y * uv.y + offset_.y;
  // Mitsuba 0.6: x = 2 * modulo(int(2u), 2) - 1 (truncation toward zero, then a non-negative modulo);
  // color0 when the two parities agree, i.e. when int(2u) + int(2v) is even.
  const long iu = static_cast<long>(u * 2), iv = static_cast<long>(v * 2);
  const long parity = ((iu + iv) % 2 + 2) % 2;
  return parity == 0 ? c0_ : c1_;
}

Color CheckerboardTexture::maxValue() const {
  return {std::fmax(c0_.r, c1_.r), std::fmax(c0_.g, c1_.g), std::fmax(c0_.b, c1_.b)};
}

// ---------------------------------------------------------------------------------------------------
// Bitmap
// ---------------------------------------------------------------------------------------------------
BitmapTexture::BitmapTexture(const std::string& filename, bool srgb, Vec2 scale, Vec2 offset)
    : scale_(scale), offset_(offset) {
  int comps = 0;
  const bool is16 = stbi_is_16_bit(filename.c_str()) != 0;
  void* data = is16 ? static_cast<void*>(stbi_load_16(filename.c_str(), &w_, &h_, &comps, 3))
                    : static_cast<void*>(stbi_load(filename.c_str(), &w_, &h_, &comps, 3));
  if (!data) throw std::runtime_error(filename + ": cannot decode image: " + stbi_failure_reason());
  if (w_ <= 0 || h_ <= 0) {
    stbi_image_free(data);
    throw std::runtime_error(filename + ": image has no pixels");
  }
  const size_t n = size_t(w_) * h_;
  texels_.resize(n);
  // 8-bit: a 256-entry decode table; 16-bit values are decoded with the same transfer function.
  float table[256];
  for (int i = 0; i < 256; ++i) table[i] = srgb ? srgbToLinear(i / 255.0f) : i / 255.0f;
  for (size_t i = 0; i < n; ++i) {
    Color c;
    for (int ch = 0; ch < 3; ++ch) {
      if (is16) {
        const float v = static_cast<const uint16_t*>(data)[3 * i + ch] / 65535.0f;
        c[ch] = srgb ? srgbToLinear(v) : v;
      } else {
        c[ch] = table[static_cast<const unsigned char*>(data)[3 * i + ch]];
      }
    }
    texels_[i] = c;
  }
  stbi_image_free(data);
  computeStats();
}

BitmapTexture::BitmapTexture(int width, int height, std::vector<Color> texels, Vec2 scale, Vec2 offset)
    : w_(width), h_(height), texels_(std::move(texels)), scale_(scale), offset_(offset) {
  if (w_ <= 0 || h_ <= 0 || texels_.size() != size_t(w_) * h_)
    throw std::runtime_error("BitmapTexture: texel count does not match " + std::to_string(w_) + "x" + std::to_string(h_));
  computeStats();
}

void BitmapTexture::computeStats() {
  double sum[3] = {0, 0, 0};
  max_ = Color(0.0f);
  for (const Color& c : texels_)
    for (int ch = 0; ch < 3; ++ch) {
      sum[ch] += c[ch];
      max_[ch] = std::fmax(max_[ch], c[ch]);
    }
  for (int ch = 0; ch < 3; ++ch) average_[ch] = float(sum[ch] / texels_.size());
}

Color BitmapTexture::eval(Vec2 uv) const {
  const float u = scale_.x * uv.x + offset_.x, v = scale_.y * uv.y + offset_.y;
  // Texel centres at (i + 0.5) / W; repeat wrapping.
  const float x = u * w_ - 0.5f, y = v * h_ - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  auto wrap = [](long i, int n) { return int(((i % n) + n) % n); };
  const int x0 = wrap(long(fx), w_), x1 = wrap(long(fx) + 1, w_);
  const int y0 = wrap(long(fy), h_), y1 = wrap(long(fy) + 1, h_);
  return (1 - ty) * ((1 - tx) * texel(x0, y0) + tx * texel(x1, y0)) +
         ty * ((1 - tx) * texel(x0, y1) + tx * texel(x1, y1));
}

// ---------------------------------------------------------------------------------------------------
std::shared_ptr<const Texture> makeTexture(const TextureDesc& d, const std::string& owner, const char* kind) {
  switch (d.type) {
    case TextureDesc::Type::Constant:
      return std::make_shared<ConstantTexture>(d.value);
    case TextureDesc::Type::Checkerboard:
      return std::make_shared<CheckerboardTexture>(d.color0, d.color1, d.uvScale, d.uvOffset);
    case TextureDesc::Type::Bitmap:
      try {
        return std::make_shared<BitmapTexture>(d.filename, d.srgb, d.uvScale, d.uvOffset);
      } catch (const std::exception& e) {
        throw std::runtime_error(std::string(kind) + " '" + owner + "': bitmap texture: " + e.what());
      }
  }
  throw std::runtime_error(std::string(kind) + " '" + owner + "': unknown texture type");
}

}  // namespace mlt
