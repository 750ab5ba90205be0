// False-colour per-pixel error maps: log10 of the relative squared error (metrics.h, relativeErrorMap)
// mapped through a perceptually ordered colour ramp (black -> purple -> orange -> yellow -> white, after
// matplotlib's "inferno") from 10^logMin (black) to 10^logMax (white). Written with the project's PNG
// writer; the colours are converted to linear first because writePng applies the sRGB curve.
#pragma once
#include <string>
#include <vector>

#include "common/core/color.h"

namespace mlt::eval {

// sRGB colour (components in [0,1]) of t in [0,1] on the ramp; t is clamped.
Color errorRampSrgb(float t);
// Linear RGB image of the map (one pixel per error value; non-finite errors are white).
std::vector<Color> errorMapImage(const std::vector<float>& relErr, float logMin = -4, float logMax = 1);
void writeErrorMapPng(const std::string& path, int width, int height, const std::vector<float>& relErr,
                      float logMin = -4, float logMax = 1);

}  // namespace mlt::eval
