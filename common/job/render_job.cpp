// The job API's method-independent parts: method names, merging partial results, and dispatch to the
// sample-based (sample_job.h) or Markov-chain (mlt_job.h) implementation.
#include "common/job/render_job.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "common/job/mlt_job.h"
#include "common/job/sample_job.h"
#include "common/render/render_scene.h"

namespace mlt {

const char* methodName(Method m) {
  switch (m) {
    case Method::PT: return "pt";
    case Method::LT: return "lt";
    case Method::BDPT: return "bdpt";
    case Method::PSSMLT: return "pssmlt";
    case Method::PSSMLT_BDPT: return "pssmlt-bdpt";
    case Method::MMLT: return "mmlt";
  }
  return "unknown";
}

Method parseMethod(const std::string& name) {
  for (Method m : {Method::PT, Method::LT, Method::BDPT, Method::PSSMLT, Method::PSSMLT_BDPT, Method::MMLT})
    if (name == methodName(m)) return m;
  throw std::invalid_argument("unknown method '" + name + "' (expected pt, lt, bdpt, pssmlt, pssmlt-bdpt or mmlt)");
}

bool isMarkovChainMethod(Method m) { return m == Method::PSSMLT || m == Method::PSSMLT_BDPT || m == Method::MMLT; }

const std::vector<std::string>& mutationKindNames(Method m) {
  static const std::vector<std::string> kelemen = {"large", "small"}, none;  // index = MutationType
  return isMarkovChainMethod(m) ? kelemen : none;
}

namespace {
void addVectors(std::vector<uint64_t>& a, const std::vector<uint64_t>& b) {
  if (a.size() < b.size()) a.resize(b.size(), 0);
  for (size_t i = 0; i < b.size(); ++i) a[i] += b[i];
}
}  // namespace

void ChainStats::add(const ChainStats& o) {
  addVectors(proposedPerLength, o.proposedPerLength);
  addVectors(acceptedPerLength, o.acceptedPerLength);
  addVectors(proposedPerKind, o.proposedPerKind);
  addVectors(acceptedPerKind, o.acceptedPerKind);
  addPerSlot(largeStepSums, o.largeStepSums);
}

void PartialResult::add(const PartialResult& o) {
  // Check everything before changing anything, so a rejected result leaves this one intact.
  std::vector<uint32_t> theirs = o.units;
  std::sort(theirs.begin(), theirs.end());
  if (std::adjacent_find(theirs.begin(), theirs.end()) != theirs.end())
    throw std::invalid_argument("PartialResult::add: work unit " +
                                std::to_string(*std::adjacent_find(theirs.begin(), theirs.end())) +
                                " appears twice in the added result");
  std::vector<uint32_t> common;
  std::set_intersection(units.begin(), units.end(), theirs.begin(), theirs.end(), std::back_inserter(common));
  if (!common.empty())
    throw std::invalid_argument("PartialResult::add: work unit " + std::to_string(common.front()) +
                                " is already included");
  const bool emptyFilm = film.width() == 0 && film.height() == 0;
  if (!emptyFilm && o.film.pixelCount() > 0 &&
      (film.width() != o.film.width() || film.height() != o.film.height()))
    throw std::invalid_argument("PartialResult::add: film size mismatch");

  if (emptyFilm) film = o.film;
  else if (o.film.pixelCount() > 0) film.merge(o.film);
  samples += o.samples;
  stats.add(o.stats);
  std::vector<uint32_t> merged;
  merged.reserve(units.size() + theirs.size());
  std::merge(units.begin(), units.end(), theirs.begin(), theirs.end(), std::back_inserter(merged));
  units = std::move(merged);
  seconds += o.seconds;
}

JobPlan planJob(const RenderScene& scene, const RenderSettings& settings) {
  RenderSettings s = settings;
  const int camW = scene.camera().width(), camH = scene.camera().height();
  // The camera's raster is built for its own film size, so a different size must be applied to the scene
  // description before the render scene is built (the CLI does this for --width/--height).
  if ((s.width != 0 && s.width != camW) || (s.height != 0 && s.height != camH))
    throw std::invalid_argument("settings: film size " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                                " differs from the scene camera's " + std::to_string(camW) + "x" +
                                std::to_string(camH) + " (set it on the scene description before building)");
  s.width = camW;
  s.height = camH;
  if (s.integrator.maxDepth < -1) throw std::invalid_argument("settings: max depth must be >= -1 (-1 = unlimited)");
  if (s.integrator.rrDepth < 0) throw std::invalid_argument("settings: rr depth must be >= 0");
  if (isMarkovChainMethod(s.method)) return planMarkovChainJob(scene, s);
  return planSampleJob(s);
}

PartialResult runWorkUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) {
  if (isMarkovChainMethod(plan.settings.method)) return runMarkovChain(scene, plan, unit);
  return runSampleUnit(scene, plan, unit);
}

std::vector<Color> developImage(const JobPlan& plan, const PartialResult& merged) {
  if (isMarkovChainMethod(plan.settings.method)) return developMarkovChainImage(plan, merged);
  return developSampleImage(plan, merged);
}

}  // namespace mlt
