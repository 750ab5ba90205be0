#include "common/job/image_metadata.h"

#include "common/mlt/chain_report.h"

namespace mlt {

ImageMetadata imageMetadata(const JobPlan& plan, const PartialResult& merged, const std::string& scene,
                            const std::string& sceneHash) {
  ImageMetadata m;
  const double pixels = double(plan.settings.width) * double(plan.settings.height);
  m.strings["software"] = "mltfarm";
  m.strings["method"] = methodName(plan.settings.method);
  m.strings["scene"] = scene;
  m.strings["sceneHash"] = sceneHash;
  m.strings["seed"] = std::to_string(plan.settings.seed);
  m.numbers["width"] = plan.settings.width;
  m.numbers["height"] = plan.settings.height;
  m.numbers["maxDepth"] = plan.settings.integrator.maxDepth;
  m.numbers["rrDepth"] = plan.settings.integrator.rrDepth;
  m.numbers["workUnits"] = double(merged.units.size());
  m.numbers["workUnitsPlanned"] = double(plan.units.size());
  m.numbers["nonFiniteSamples"] = double(merged.film.nonFiniteSamples());
  if (isMarkovChainMethod(plan.settings.method)) {
    addChainMetadata(makeChainReport(plan, merged), m);  // includes the chain settings (largeStepProb, ...)
  } else {
    m.numbers["samples"] = double(merged.samples);
    m.numbers["spp"] = double(merged.samples) / pixels;
  }
  return m;
}

}  // namespace mlt
