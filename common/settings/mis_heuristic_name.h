// The text names of MisHeuristic, one mapping for the command line, the wire and the EXR metadata.
#pragma once
#include <optional>
#include <string_view>

#include "common/settings/render_settings.h"

namespace mlt {

// "power" (the default, exponent 2) or "balance".
inline const char* misHeuristicName(MisHeuristic h) { return h == MisHeuristic::Balance ? "balance" : "power"; }

// The inverse of misHeuristicName; nullopt for any other text.
inline std::optional<MisHeuristic> misHeuristicFromName(std::string_view name) {
  for (MisHeuristic h : {MisHeuristic::Power, MisHeuristic::Balance})
    if (name == misHeuristicName(h)) return h;
  return std::nullopt;
}

}  // namespace mlt
