#include "common/scene/material_tables.h"

#include <algorithm>
#include <cctype>

namespace mlt {
namespace {

struct IorEntry {
  const char* name;
  float ior;
};
// Mitsuba 0.6 / 3 (src/libcore/util.cpp / include/mitsuba/core/ior.h), at 589 nm.
constexpr IorEntry kIor[] = {
    {"vacuum", 1.0f},          {"helium", 1.000036f},        {"hydrogen", 1.000132f},
    {"air", 1.000277f},        {"carbon dioxide", 1.00045f}, {"water", 1.3330f},
    {"acetone", 1.36f},        {"ethanol", 1.361f},          {"carbon tetrachloride", 1.461f},
    {"glycerol", 1.4729f},     {"benzene", 1.501f},          {"silicone oil", 1.52045f},
    {"bromine", 1.661f},       {"water ice", 1.31f},         {"fused quartz", 1.458f},
    {"pyrex", 1.470f},         {"acrylic glass", 1.49f},     {"polypropylene", 1.49f},
    {"bk7", 1.5046f},          {"sodium chloride", 1.544f},  {"amber", 1.55f},
    {"pet", 1.5750f},          {"diamond", 2.419f},
};

struct ConductorEntry {
  const char* name;
  Color eta, k;
};
// RGB reductions of the measured spectra Mitsuba ships (the same values pbrt-v3 and Tungsten use).
const ConductorEntry kConductors[] = {
    {"Ag", {0.1552646489f, 0.1167232965f, 0.1383806959f}, {4.8283433224f, 3.1222459278f, 2.1469504455f}},
    {"Al", {1.6574599595f, 0.8803689579f, 0.5212287346f}, {9.2238691996f, 6.2695232477f, 4.8370012281f}},
    {"Au", {0.1431189557f, 0.3749570432f, 1.4424785571f}, {3.9831604247f, 2.3857207478f, 1.6032152899f}},
    {"Cr", {4.3696828663f, 2.9167024892f, 1.6547005413f}, {5.2064337956f, 4.2313645277f, 3.7549467933f}},
    {"Cu", {0.2004376970f, 0.9240334304f, 1.1022119527f}, {3.9129485033f, 2.4528477015f, 2.1421879552f}},
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

}  // namespace

std::optional<float> lookupIor(const std::string& name) {
  const std::string n = lower(name);
  for (const auto& e : kIor)
    if (n == e.name) return e.ior;
  return std::nullopt;
}

std::optional<std::pair<Color, Color>> lookupConductor(const std::string& name) {
  const std::string n = lower(name);
  for (const auto& e : kConductors)
    if (n == lower(e.name)) return std::make_pair(e.eta, e.k);
  return std::nullopt;
}

std::string knownIorNames() {
  std::string s;
  for (const auto& e : kIor) s += (s.empty() ? "" : ", ") + std::string(e.name);
  return s;
}

std::string knownConductorNames() {
  std::string s;
  for (const auto& e : kConductors) s += (s.empty() ? "" : ", ") + std::string(e.name);
  return s + ", none";
}

}  // namespace mlt
