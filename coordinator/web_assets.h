// The web page's static files (coordinator/web/), embedded in the binary at build time by
// coordinator/web/embed.cmake: no files to install beside the coordinator, no build step for the page.
#pragma once
#include <cstddef>
#include <string>

namespace mlt::farm {

struct WebAsset {
  const char* path;         // "/index.html", "/app.js", ...
  const char* contentType;
  const unsigned char* data;
  size_t size;
};

// nullptr when there is no such file.
const WebAsset* findWebAsset(const std::string& path);

}  // namespace mlt::farm
