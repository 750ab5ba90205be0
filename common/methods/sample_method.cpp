#include "common/methods/sample_method.h"

#include <stdexcept>
#include <string>

#include "common/io/exr_io.h"
#include "common/job/sample_job.h"

namespace mlt {

void SampleMethod::validate(const RenderSettings& s) const {
  RenderMethod::validate(s);
  if (s.spp < 1) throw std::invalid_argument("settings: spp must be >= 1, got " + std::to_string(s.spp));
  if (s.samplesPerUnit < 0)
    throw std::invalid_argument("settings: samples per unit must be >= 0, got " + std::to_string(s.samplesPerUnit));
}

JobPlan SampleMethod::plan(const RenderScene& /*scene*/, const RenderSettings& settings) const {
  return planSampleJob(settings);
}

PartialResult SampleMethod::runUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) const {
  const std::unique_ptr<PathEvaluator> evaluator = makeEvaluator(scene, plan.settings);
  return runSampleUnit(*evaluator, plan, unit);
}

std::vector<Color> SampleMethod::develop(const JobPlan& plan, const PartialResult& merged) const {
  return developSampleImage(plan, merged);
}

void SampleMethod::addMetadata(const JobPlan& plan, const PartialResult& merged, ImageMetadata& m) const {
  const double pixels = double(plan.settings.width) * double(plan.settings.height);
  m.numbers["samples"] = double(merged.samples);
  m.numbers["spp"] = double(merged.samples) / pixels;
}

}  // namespace mlt
