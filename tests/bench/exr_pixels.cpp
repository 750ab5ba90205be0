// exr_pixels A.exr [B.exr]: prints an EXR's size, the SHA-256 of its pixels (the float bytes r, g, b per
// pixel, row-major, as tests/golden_images_test.cpp hashes them) and its metadata keys; given two files,
// exits 0 only if their pixels are bit-identical (the metadata may differ: a farm job id, a wall time).
// Used by tests/bench/farm_overhead.sh to check that the farm and --in-process rendered the same image.
#include <cstdio>
#include <cstring>
#include <exception>

#include "common/core/sha256.h"
#include "common/io/exr_io.h"

namespace {

std::string pixelDigest(const mlt::ExrImage& img) {
  mlt::Sha256 sha;
  for (const mlt::Color& c : img.rgb) {
    const float v[3] = {c.r, c.g, c.b};
    sha.update(v, sizeof v);
  }
  return sha.hexDigest();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: exr_pixels A.exr [B.exr]\n");
    return 2;
  }
  try {
    std::string digests[2];
    for (int i = 1; i < argc; ++i) {
      const mlt::ExrImage img = mlt::readExr(argv[i]);
      digests[i - 1] = pixelDigest(img);
      std::printf("%s: %dx%d pixels sha256 %s, %zu metadata keys\n", argv[i], img.width, img.height,
                  digests[i - 1].c_str(), img.metadata.numbers.size() + img.metadata.strings.size());
    }
    if (argc == 3) {
      const bool same = digests[0] == digests[1];
      std::printf("pixels %s\n", same ? "identical" : "DIFFER");
      return same ? 0 : 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "exr_pixels: %s\n", e.what());
    return 2;
  }
}
