// Mitsuba's named optical constants: dielectric IORs (Mitsuba's "IOR table") and a small table of
// conductors as RGB complex IORs (eta, k) at the sRGB primaries' dominant wavelengths.
#pragma once
#include <optional>
#include <string>
#include <utility>

#include "common/core/color.h"

namespace mlt {

// Case-insensitive; e.g. "vacuum" 1.0, "air" 1.000277, "bk7" 1.5046, "water" 1.333, "diamond" 2.419.
std::optional<float> lookupIor(const std::string& name);

// {eta, k} for Mitsuba conductor presets we carry (Ag, Al, Au, Cr, Cu, ...); nullopt if unknown.
// "none" is handled by the caller (ideal mirror).
std::optional<std::pair<Color, Color>> lookupConductor(const std::string& name);

// Comma-separated names, for error messages.
std::string knownIorNames();
std::string knownConductorNames();

}  // namespace mlt
