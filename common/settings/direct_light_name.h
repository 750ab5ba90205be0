// The text names of DirectLight, one mapping for the command line, the wire and the EXR metadata.
#pragma once
#include <optional>
#include <string_view>

#include "common/settings/render_settings.h"

namespace mlt {

// "auto", "chains", "separate", "emission".
inline const char* directLightName(DirectLight d) {
  switch (d) {
    case DirectLight::Chains: return "chains";
    case DirectLight::Separate: return "separate";
    case DirectLight::Emission: return "emission";
    case DirectLight::Auto: break;
  }
  return "auto";
}

// The inverse of directLightName; nullopt for any other text.
inline std::optional<DirectLight> directLightFromName(std::string_view name) {
  for (DirectLight d : {DirectLight::Auto, DirectLight::Chains, DirectLight::Separate, DirectLight::Emission})
    if (name == directLightName(d)) return d;
  return std::nullopt;
}

}  // namespace mlt
