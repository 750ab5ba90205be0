// The text names of MltSplatting, one mapping for the command line, the wire and the EXR metadata.
#pragma once
#include <optional>
#include <string_view>

#include "common/settings/render_settings.h"

namespace mlt {

// "kelemen-mis", "expected-value"; "" for MethodDefault (the method's, resolved at planning).
inline const char* splattingName(MltSplatting s) {
  switch (s) {
    case MltSplatting::KelemenMIS: return "kelemen-mis";
    case MltSplatting::ExpectedValue: return "expected-value";
    case MltSplatting::MethodDefault: break;
  }
  return "";
}

// The inverse of splattingName; nullopt for any other text.
inline std::optional<MltSplatting> splattingFromName(std::string_view name) {
  for (MltSplatting s : {MltSplatting::MethodDefault, MltSplatting::ExpectedValue, MltSplatting::KelemenMIS})
    if (name == splattingName(s)) return s;
  return std::nullopt;
}

}  // namespace mlt
