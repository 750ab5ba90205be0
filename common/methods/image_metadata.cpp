#include "common/methods/image_metadata.h"

#include "common/methods/registry.h"
#include "common/settings/mis_heuristic_name.h"

namespace mlt {

ImageMetadata imageMetadata(const JobPlan& plan, const PartialResult& merged, const std::string& scene,
                            const std::string& sceneHash) {
  ImageMetadata m;
  m.strings["software"] = "mltfarm";
  m.strings["method"] = plan.settings.method;
  m.strings["scene"] = scene;
  m.strings["sceneHash"] = sceneHash;
  m.strings["seed"] = std::to_string(plan.settings.seed);
  m.numbers["width"] = plan.settings.width;
  m.numbers["height"] = plan.settings.height;
  m.numbers["maxDepth"] = plan.settings.integrator.maxDepth;
  m.numbers["rrDepth"] = plan.settings.integrator.rrDepth;
  // Only when not the default, so that a default render's bytes stay those of every earlier version.
  if (plan.settings.integrator.heuristic != MisHeuristic::Power)
    m.strings["misHeuristic"] = misHeuristicName(plan.settings.integrator.heuristic);
  m.numbers["workUnits"] = double(merged.units.size());
  m.numbers["workUnitsPlanned"] = double(plan.units.size());
  m.numbers["nonFiniteSamples"] = double(merged.film.nonFiniteSamples());
  findMethod(plan.settings.method).addMetadata(plan, merged, m);
  return m;
}

}  // namespace mlt
