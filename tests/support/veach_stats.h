// Image statistics of veach-mlt rendered through its job functions (common/methods/veach/veach_job.h:
// plan -> every chain -> merge in unit order -> develop) with `runs` job seeds seed0, seed0 + 1, ...:
// mean and standard error over runs of the image mean and tiles x tiles tile means (luminance), in the
// layout of test::ImageStats. `acceptance` (optional) receives the per-mutation acceptance of all runs.
#pragma once
#include <cstdint>
#include <string>

#include "common/job/job_types.h"
#include "common/settings/render_settings.h"
#include "common/methods/veach/mutations.h"
#include "tests/support/estimates.h"

namespace mlt::test {

ImageStats veachStats(const RenderScene& scene, RenderSettings settings, const veach::MutationSettings& mutations,
                      int runs, int tiles, uint64_t seed0, std::string* acceptance = nullptr);

// Mean and standard error over runs of per-run vectors (image mean, tile means).
ImageStats statsOverRuns(const std::vector<std::vector<double>>& values, int tiles);
// Image mean and tile means (luminance) of a developed image.
std::vector<double> tileMeans(const std::vector<Color>& image, int width, int height, int tiles);

}  // namespace mlt::test
