#include "tools/eval/error_map.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/io/png_io.h"

namespace mlt::eval {

namespace {
// Control points of the ramp (sRGB), evenly spaced in t; sampled from "inferno".
constexpr Color kRamp[] = {{0.001f, 0.000f, 0.014f}, {0.258f, 0.039f, 0.406f}, {0.578f, 0.148f, 0.404f},
                           {0.865f, 0.317f, 0.226f}, {0.988f, 0.645f, 0.040f}, {0.988f, 0.998f, 0.645f}};
constexpr int kRampSize = sizeof(kRamp) / sizeof(kRamp[0]);

float srgbToLinear(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }
}  // namespace

Color errorRampSrgb(float t) {
  if (!(t > 0)) t = 0;  // also maps NaN to 0
  t = std::min(t, 1.0f);
  float x = t * (kRampSize - 1);
  int i = std::min(int(x), kRampSize - 2);
  float f = x - float(i);
  return kRamp[i] * (1 - f) + kRamp[i + 1] * f;
}

std::vector<Color> errorMapImage(const std::vector<float>& relErr, float logMin, float logMax) {
  if (!(logMax > logMin)) throw std::invalid_argument("errorMapImage: logMax must exceed logMin");
  std::vector<Color> img(relErr.size());
  for (size_t i = 0; i < relErr.size(); ++i) {
    float e = relErr[i];
    float t = std::isfinite(e) ? (e > 0 ? (std::log10(e) - logMin) / (logMax - logMin) : 0.f) : 1.f;
    Color s = errorRampSrgb(t);
    img[i] = {srgbToLinear(s.r), srgbToLinear(s.g), srgbToLinear(s.b)};
  }
  return img;
}

void writeErrorMapPng(const std::string& path, int width, int height, const std::vector<float>& relErr,
                      float logMin, float logMax) {
  if (size_t(width) * size_t(height) != relErr.size())
    throw std::invalid_argument(path + ": error map size does not match " + std::to_string(width) + "x" +
                                std::to_string(height));
  writePng(path, width, height, errorMapImage(relErr, logMin, logMax), 0.f);
}

}  // namespace mlt::eval
