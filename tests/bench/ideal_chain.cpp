// ideal_chain REFERENCE.exr MUTATIONS [EPS]: the relMSE an ideal Markov chain (independent draws from
// its target: perfect mixing) would reach with MUTATIONS mutations on the reference's image, for the
// luminance target, a uniform one and the best one (tools/eval/ideal_chain.h (I1)). Put next to a run's
// relMSE at the same mutation count (the harness's `samples` column), the ratio is what the chain's
// correlation costs; next to pt's at equal time, whether a chain could beat it at all.
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "common/io/exr_io.h"
#include "tools/eval/ideal_chain.h"

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::fprintf(stderr, "usage: ideal_chain REFERENCE.exr MUTATIONS [EPS (default 0.01)]\n");
    return 2;
  }
  try {
    const mlt::ExrImage ref = mlt::readExr(argv[1]);
    char* end = nullptr;
    const double n = std::strtod(argv[2], &end);
    if (*end != '\0' || !(n > 0)) {
      std::fprintf(stderr, "ideal_chain: MUTATIONS '%s' is not a positive number\n", argv[2]);
      return 2;
    }
    double eps = 1e-2;
    if (argc == 4) {
      eps = std::strtod(argv[3], &end);
      if (*end != '\0' || !(eps > 0)) {
        std::fprintf(stderr, "ideal_chain: EPS '%s' is not a positive number\n", argv[3]);
        return 2;
      }
    }
    const mlt::eval::IdealChainBounds b = mlt::eval::idealChainBounds(ref.rgb, n, eps);
    const double P = double(ref.rgb.size());
    std::printf("%s: %dx%d, %.4g mutations (%.1f per pixel), eps %g\n", argv[1], ref.width, ref.height, n, n / P, eps);
    std::printf("ideal chain relMSE: luminance target %.4g, uniform %.4g, best %.4g\n", b.luminance, b.uniform, b.best);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ideal_chain: %s\n", e.what());
    return 1;
  }
}
