// Image statistics of a Markov chain method rendered through the job API (plan -> every unit -> merge in
// unit order -> develop) with `runs` independent job seeds (seed0, seed0 + 1, ...): the mean and standard
// error over runs of the image mean and of tiles x tiles tile means (luminance; width and height must be
// multiples of tiles, so that pixel tiles match the raster tiles of estimateImage), in the layout of
// test::ImageStats (tests/support/estimates.h). The bootstrap runs in every run, so the spread includes
// b's own error.
#pragma once
#include <cstdint>

#include "common/methods/registry.h"
#include "tests/support/estimates.h"

namespace mlt::test {

ImageStats markovChainStats(const RenderScene& scene, RenderSettings settings, int width, int height, int runs,
                            int tiles, uint64_t seed0 = 1000);

}  // namespace mlt::test
