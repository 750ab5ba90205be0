// The importance pilot: a short path-traced image of the film, tile by tile, from which the relative
// target's importance map is made (common/mlt/importance.h (R2)).
//
// pt samples (next-event estimation and MIS, the job's integrator settings), a few per pixel, at a hashed
// position in the pixel, keyed by (job seed, pixel) on a stream of its own: independent of the bootstrap's
// candidates and of every chain's numbers, so that the map is fixed before any sample of b is drawn and
// b^ stays unbiased (a map that depended on b's own samples would not). pt is the cheapest estimator of
// the whole image per sample (on the bundled scenes 2-3x bdpt's samples per second); its misses
// (caustics that only paths hitting the light reach) give their tiles a larger h, so more of the chains'
// mutations, and make the rare paths there peaks of the target (caustic-mirror: importance.h). At 256 x 256
// the map has 4 x 4-pixel tiles (importanceTileSize), each tile's g pools the 3 x 3 tiles around it: 288
// samples.
// A pure function of (scene, seed, film, integrator settings, floor).
#pragma once
#include <cstdint>

#include "common/mlt/importance.h"
#include "common/settings/render_settings.h"

namespace mlt {

class RenderScene;

// The pilot's samples behind each tile's g (a 3 x 3 box of tiles): samples per pixel are
// ceil(kImportancePooledSamples / (9 T^2)), 2 at 256 x 256 (T = 4), 29 on a 24 x 24 film (T = 1).
constexpr uint32_t kImportancePooledSamples = 256;

struct ImportancePilot {
  ImportanceMap map;     // empty where the pilot saw no light
  double floor = 0;      // the kappa it was made with
  uint64_t samples = 0;  // pt samples traced
  double cost = 0;       // in the bootstrap's unit (numbers drawn + kCandidateOverhead per sample)
  double seconds = 0;    // wall time
};

ImportancePilot importancePilot(const RenderScene& scene, const RenderSettings& settings, double floor,
                                bool parallel = true);

}  // namespace mlt
