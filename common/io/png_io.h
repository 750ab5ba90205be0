// PNG preview output: linear RGB -> exposure -> clamp to [0,1] -> sRGB transfer curve -> 8 bits (libpng).
// Non-finite values are written as 0. Errors are std::runtime_error naming the file.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/core/color.h"

namespace mlt {

// sRGB-encoded 8-bit value of a linear value scaled by 2^exposureStops.
uint8_t toSrgb8(float linear, float exposureScale);

void writePng(const std::string& path, int width, int height, const std::vector<Color>& rgb,
              float exposureStops = 0.f);

}  // namespace mlt
