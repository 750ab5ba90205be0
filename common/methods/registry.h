// The registry of rendering methods, and the job API over it. Everything above common/ (CLI, coordinator,
// worker, merge tool, evaluation harness) finds a method here by name and calls it through the
// RenderMethod interface; nothing switches on a method.
//
// The built-in methods are listed once, in registry.cpp (one line per method folder). A program or a test
// may add its own with registerMethod before it plans jobs (tests/toy_method_test.cpp does).
#pragma once
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "common/job/job_types.h"
#include "common/methods/method.h"

namespace mlt {

// Throws std::invalid_argument naming the value and listing the registered names.
const RenderMethod& findMethod(const std::string& name);
bool hasMethod(const std::string& name);
// Every registered method, built-ins first in registry order.
std::vector<const RenderMethod*> allMethods();
std::string methodNameList();  // "pt, lt, bdpt, ..." (for help texts and errors)
// Adds a method; throws std::invalid_argument if its name is taken or one of its params' names is
// used by another method with a different type.
void registerMethod(std::unique_ptr<RenderMethod> method);

// Shorthands over findMethod.
bool isMarkovChainMethod(const std::string& method);
const std::vector<std::string>& mutationKindNames(const std::string& method);

// ---- the job API ----
// Resolves the film size against the scene camera, checks the common settings, then the method plans.
JobPlan planJob(const RenderScene& scene, const RenderSettings& settings);
PartialResult runWorkUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit);
// Linear RGB, row-major from the top-left. All normalization happens here.
std::vector<Color> developImage(const JobPlan& plan, const PartialResult& merged);

// Units [begin, end) of `plan`, up to `parallelism` at a time, summed in index order into a zero partial of the
// plan's film size (executor.h). Returns false (result incomplete) if `cancel` became true between units.
bool runUnits(const RenderScene& scene, const JobPlan& plan, uint32_t begin, uint32_t end, PartialResult& out,
              const std::atomic<bool>* cancel = nullptr, size_t parallelism = 1);

}  // namespace mlt
