// Runs one complete render job in this process through the job API (planJob -> runWorkUnit for every
// unit, in parallel -> PartialResult::add in unit-index order -> developImage), exactly as the CLI's
// in-process renderer does, and keeps the per-unit chain statistics the stability analysis needs.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/methods/registry.h"
#include "common/scene/scene_desc.h"

namespace mlt::eval {

struct JobRun {
  JobPlan plan;
  PartialResult merged;
  std::vector<Color> image;            // developed linear RGB
  double seconds = 0;                  // wall time of planning (bootstrap) + all units + development
  double planSeconds = 0;              // of which planning (the Markov chain methods' bootstrap)
  std::vector<ChainStats> unitStats;   // per work unit, in index order (chains: one per chain)
  std::vector<uint64_t> unitSamples;   // per work unit: mutations (chains) or pixel samples
};

// threads <= 0: every core.
JobRun runJobInProcess(const RenderScene& scene, const RenderSettings& settings, int threads);

// Content hash of a scene (FNV-1a 64 over the scene file and every file it references, names relative
// to the scene's directory), hex. Used to key cached references.
std::string sceneContentHash(const SceneDesc& desc);
uint64_t fnv1a64(const std::string& bytes, uint64_t h = 0xcbf29ce484222325ULL);

}  // namespace mlt::eval
