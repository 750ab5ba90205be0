// PNG preview writer via libpng.
#include "common/io/png_io.h"

#include <png.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

namespace mlt {

uint8_t toSrgb8(float linear, float exposureScale) {
  float v = linear * exposureScale;
  if (!std::isfinite(v) || v <= 0.f) return 0;  // NaN, -inf, negative -> 0; +inf handled below
  v = std::fmin(v, 1.f);
  // IEC 61966-2-1 transfer function.
  const float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(std::fmin(std::fmax(s, 0.f), 1.f) * 255.f));
}

void writePng(const std::string& path, int width, int height, const std::vector<Color>& rgb,
              float exposureStops) {
  if (width <= 0 || height <= 0) throw std::runtime_error(path + ": cannot write an empty PNG");
  if (rgb.size() != size_t(width) * size_t(height))
    throw std::runtime_error(path + ": pixel count does not match " + std::to_string(width) + "x" +
                             std::to_string(height));
  const float scale = std::exp2(exposureStops);
  std::vector<uint8_t> bytes(size_t(width) * size_t(height) * 3);
  for (size_t i = 0; i < rgb.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const float v = rgb[i][c];
      // +inf is "brighter than white"; NaN is not a value and becomes black.
      bytes[3 * i + c] = (std::isinf(v) && v > 0) ? 255 : toSrgb8(v, scale);
    }
  }

  std::unique_ptr<FILE, int (*)(FILE*)> fp(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!fp) throw std::runtime_error(path + ": cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) throw std::runtime_error(path + ": png_create_write_struct failed");
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw std::runtime_error(path + ": png_create_info_struct failed");
  }
  std::vector<png_bytep> rows(height);
  for (int y = 0; y < height; ++y) rows[y] = bytes.data() + size_t(y) * size_t(width) * 3;
  // libpng reports errors by longjmp; nothing with a destructor is created between here and the end.
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error(path + ": libpng failed while writing");
  }
  png_init_io(png, fp.get());
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
}

}  // namespace mlt
