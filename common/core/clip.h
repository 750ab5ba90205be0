// Echoing client input in error messages: a short prefix and the full length, never the whole (a 1 MiB
// job id or an 8 MiB attribute value must not come back whole in a reply or fill a log).
#pragma once
#include <string>
#include <string_view>

namespace mlt {

// `s` cut to its first `maxChars` characters plus "...(N bytes)" when longer.
inline std::string clipForMessage(std::string_view s, size_t maxChars = 80) {
  if (s.size() <= maxChars) return std::string(s);
  return std::string(s.substr(0, maxChars)) + "...(" + std::to_string(s.size()) + " bytes)";
}

}  // namespace mlt
