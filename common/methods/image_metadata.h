// The EXR header keys every developed image carries, whichever path rendered it (`mltfarm render
// --in-process`, the coordinator, `mltfarm merge`). Paths add their own keys (wall-clock times, farm ids)
// on top; keys that depend only on the plan and the merged result are written here, once.
#pragma once
#include <string>

#include "common/io/exr_io.h"
#include "common/job/job_types.h"

namespace mlt {

// software, method, scene, sceneHash, seed (a string: 64-bit seeds do not fit a double), width, height,
// maxDepth, rrDepth, workUnits (merged), workUnitsPlanned, nonFiniteSamples; Markov chains: the chain
// report (b, b_k, acceptance, ...; chain_report.h); pt/lt/bdpt: samples and spp: the method's
// RenderMethod::addMetadata.
ImageMetadata imageMetadata(const JobPlan& plan, const PartialResult& merged, const std::string& scene,
                            const std::string& sceneHash);

}  // namespace mlt
