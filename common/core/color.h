// RGB radiometric quantity (radiance, importance, throughput, BSDF value). Linear Rec.709/sRGB primaries.
#pragma once
#include <cmath>

#include "common/core/vec.h"

namespace mlt {

struct Color {
  float r = 0, g = 0, b = 0;
  constexpr Color() = default;
  constexpr Color(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}
  constexpr explicit Color(float v) : r(v), g(v), b(v) {}
  constexpr float operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
  constexpr float& operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
  Color& operator+=(const Color& o) { r += o.r; g += o.g; b += o.b; return *this; }
  Color& operator*=(const Color& o) { r *= o.r; g *= o.g; b *= o.b; return *this; }
  Color& operator*=(float s) { r *= s; g *= s; b *= s; return *this; }
  bool isBlack() const { return r == 0 && g == 0 && b == 0; }
  bool isFinite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
  float maxComponent() const { return fmaxNum(r, fmaxNum(g, b)); }
  float average() const { return (r + g + b) * (1.0f / 3.0f); }
};
inline constexpr Color operator+(const Color& a, const Color& b) { return {a.r + b.r, a.g + b.g, a.b + b.b}; }
inline constexpr Color operator-(const Color& a, const Color& b) { return {a.r - b.r, a.g - b.g, a.b - b.b}; }
inline constexpr Color operator*(const Color& a, const Color& b) { return {a.r * b.r, a.g * b.g, a.b * b.b}; }
inline constexpr Color operator*(const Color& a, float s) { return {a.r * s, a.g * s, a.b * s}; }
inline constexpr Color operator*(float s, const Color& a) { return {a.r * s, a.g * s, a.b * s}; }
inline constexpr Color operator/(const Color& a, float s) { return {a.r / s, a.g / s, a.b / s}; }
inline Color operator/(const Color& a, const Color& b) {
  return {b.r != 0 ? a.r / b.r : 0.f, b.g != 0 ? a.g / b.g : 0.f, b.b != 0 ? a.b / b.b : 0.f};
}

// Luminance (Rec.709 Y). This is the Markov chains' scalar target function c(x) (see mlt/target.h).
inline constexpr float luminance(const Color& c) { return 0.212671f * c.r + 0.715160f * c.g + 0.072169f * c.b; }

}  // namespace mlt
