// The registry: the built-in methods, one line per method folder, plus any registered at run time.
#include "common/methods/registry.h"

#include <fmt/format.h>

#include <map>
#include <mutex>
#include <stdexcept>

#include "common/job/executor.h"
#include "common/methods/bdpt/bdpt_method.h"
#include "common/methods/lt/lt_method.h"
#include "common/methods/mmlt/mmlt_method.h"
#include "common/methods/pssmlt/pssmlt_method.h"
#include "common/methods/pssmlt_bdpt/pssmlt_bdpt_method.h"
#include "common/methods/pt/pt_method.h"
#include "common/methods/rjmlt/rjmlt_method.h"
#include "common/methods/veach/veach_method.h"
#include "common/render/render_scene.h"

namespace mlt {

namespace {

struct Registry {
  std::mutex mutex;
  std::vector<std::unique_ptr<RenderMethod>> methods;

  Registry() {
    // ---- the built-in methods: one line each ----
    methods.push_back(std::make_unique<PtMethod>());
    methods.push_back(std::make_unique<LtMethod>());
    methods.push_back(std::make_unique<BdptMethod>());
    methods.push_back(std::make_unique<PssmltMethod>());
    methods.push_back(std::make_unique<PssmltBdptMethod>());
    methods.push_back(std::make_unique<MmltMethod>());
    methods.push_back(std::make_unique<RjmltMethod>());
    methods.push_back(std::make_unique<VeachMltMethod>());
  }
};

Registry& registry() {
  static Registry r;
  return r;
}

const RenderMethod* lookup(const std::string& name) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  for (const auto& m : r.methods)
    if (m->name() == name) return m.get();
  return nullptr;
}

}  // namespace

std::vector<const RenderMethod*> allMethods() {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  std::vector<const RenderMethod*> out;
  for (const auto& m : r.methods) out.push_back(m.get());
  return out;
}

std::string methodNameList() {
  std::string out;
  for (const RenderMethod* m : allMethods()) out += (out.empty() ? "" : ", ") + m->name();
  return out;
}

bool hasMethod(const std::string& name) { return lookup(name) != nullptr; }

const RenderMethod& findMethod(const std::string& name) {
  if (const RenderMethod* m = lookup(name)) return *m;
  throw std::invalid_argument(fmt::format("unknown method '{}' (expected one of: {})", name, methodNameList()));
}

void registerMethod(std::unique_ptr<RenderMethod> method) {
  if (!method) throw std::invalid_argument("registerMethod: null method");
  const std::string name = method->name();
  if (name.empty()) throw std::invalid_argument("registerMethod: a method needs a name");
  for (const RenderMethod* m : allMethods()) {
    if (m->name() == name) throw std::invalid_argument("registerMethod: method '" + name + "' is already registered");
    for (const ParamSpec& theirs : m->params())
      for (const ParamSpec& ours : method->params())
        if (theirs.name == ours.name && theirs.type != ours.type)
          throw std::invalid_argument(fmt::format("registerMethod: parameter '{}' of '{}' has another type in '{}'",
                                                  ours.name, name, m->name()));
  }
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.methods.push_back(std::move(method));
}

bool isMarkovChainMethod(const std::string& method) {
  return findMethod(method).family() == MethodFamily::MarkovChain;
}

const std::vector<std::string>& mutationKindNames(const std::string& method) {
  // Cached per name: callers keep the reference (the registry never removes a method).
  static std::mutex mutex;
  static std::map<std::string, std::vector<std::string>> cache;
  const RenderMethod& m = findMethod(method);
  std::lock_guard lock(mutex);
  auto it = cache.find(method);
  if (it == cache.end()) it = cache.emplace(method, m.mutationKinds()).first;
  return it->second;
}

JobPlan planJob(const RenderScene& scene, const RenderSettings& settings) {
  const RenderMethod& method = findMethod(settings.method);
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
  method.validate(s);
  return method.plan(scene, s);
}

PartialResult runWorkUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) {
  return findMethod(plan.settings.method).runUnit(scene, plan, unit);
}

std::vector<Color> developImage(const JobPlan& plan, const PartialResult& merged) {
  return findMethod(plan.settings.method).develop(plan, merged);
}

bool runUnits(const RenderScene& scene, const JobPlan& plan, uint32_t begin, uint32_t end, PartialResult& out,
              const std::atomic<bool>* cancel, size_t parallelism) {
  if (begin > end || end > plan.units.size())
    throw std::invalid_argument("runUnits: units [" + std::to_string(begin) + ", " + std::to_string(end) +
                                ") outside the plan's " + std::to_string(plan.units.size()));
  out = emptyPartial(plan);
  UnitExecution e;
  e.issue = [&](size_t i) { return begin + i < end && !(cancel && cancel->load()); };
  e.run = [&](size_t i) { return runWorkUnit(scene, plan, plan.units[begin + i]); };
  e.merge = [&](size_t, PartialResult& r) { out.add(r); };
  e.parallelism = parallelism;
  return executeUnits(e) == size_t(end - begin);
}

}  // namespace mlt
