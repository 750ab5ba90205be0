// A rendering method is one folder, common/methods/<name>/, and implements this interface. The registry
// (registry.h) lists them; the CLI, the coordinator, the worker, the merge tool and the evaluation harness
// ask the registry and never switch on a method. Adding a method = one new folder + one line in
// registry.cpp + its tests (a test can also register one at run time: tests/toy_method_test.cpp).
//
// A job runs through a method in three steps, all pure functions of their inputs so that the farm and
// the local renderer give the same bytes:
//   plan(scene, settings)       -> JobPlan: resolved settings, normalization inputs (bootstrap), work units
//   runUnit(scene, plan, unit)  -> PartialResult: raw film sums + counts + statistics (never normalized)
//   develop(plan, merged)       -> the image: the only place where normalization is applied
// Two families share most of that code (family() says which settings group a method reads, and which
// work measure the tools budget: samples per pixel or mutations per pixel):
//   SampleMethod (sample_method.h):          batches of independent pixel samples (pt, lt, bdpt)
//   PrimarySampleChainMethod (pss_method.h): Markov chains over primary samples with a bootstrap
//                                            (pssmlt, pssmlt-bdpt, mmlt)
// A method may also implement RenderMethod directly.
#pragma once
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/job/job_types.h"
#include "common/settings/render_settings.h"

namespace mlt {

class RenderScene;
struct ImageMetadata;

enum class MethodFamily {
  Samples,      // reads spp / samplesPerUnit; work measured in samples per pixel
  MarkovChain,  // reads the chain settings; work measured in mutations per pixel
};

// One of a method's own parameters (RenderSettings::params). The CLI offers it as --<name>, the wire
// carries it by name, the EXR metadata records it.
struct ParamSpec {
  enum class Type { Double, Int, Bool, Choice };
  std::string name;                  // lower-case words joined by '-', unique among all methods' params
  Type type = Type::Double;
  std::string defaultValue;          // used when the settings do not set it
  std::string help;
  double min = 0, max = 0;           // Double/Int: allowed range [min, max] (max < min: unbounded above)
  std::vector<std::string> choices;  // Choice: the allowed values
};

class RenderMethod {
 public:
  virtual ~RenderMethod() = default;
  virtual std::string name() const = 0;         // "pt", "mmlt", ...: what --method takes
  virtual std::string description() const = 0;  // one line for --help
  virtual MethodFamily family() const = 0;
  // The names of its mutation kinds, index = Proposal::kind (common/mlt/chain.h); statistics and metadata
  // keys use them. Empty for methods without Markov chains.
  virtual std::vector<std::string> mutationKinds() const { return {}; }
  // Its own parameters with their defaults (RenderSettings::params).
  virtual std::vector<ParamSpec> params() const { return {}; }
  // Throws std::invalid_argument naming the setting if a job cannot be planned with these settings
  // (width/height may still be 0 = the scene's). Cheap: the coordinator calls it at submission. The
  // default checks the common settings and the params against params().
  virtual void validate(const RenderSettings& settings) const;
  // settings.width/height are resolved against the scene camera by planJob (registry.h) before this.
  virtual JobPlan plan(const RenderScene& scene, const RenderSettings& settings) const = 0;
  virtual PartialResult runUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit) const = 0;
  // Linear RGB, row-major from the top-left.
  virtual std::vector<Color> develop(const JobPlan& plan, const PartialResult& merged) const = 0;
  // The EXR keys that describe this method's result (imageMetadata in image_metadata.h adds the common
  // ones): samples and spp, or the chain report (b, acceptance per kind and per path length, ...).
  virtual void addMetadata(const JobPlan& plan, const PartialResult& merged, ImageMetadata& metadata) const = 0;
  // The work a unit of the plan holds, in the family's measure (samples or mutations): progress, ETA.
  virtual uint64_t unitWork(const JobPlan& plan, const WorkUnit& unit) const;
  // The splat layers a film of the plan holds (layer 0 included): what a task's film costs to move and
  // sum (farm/tasks.h splitTasks). The default: the chain layout of develop.h for Markov chains, else 1.
  virtual size_t filmLayers(const JobPlan& plan) const;

  // Throws std::invalid_argument unless every entry names one of params() and holds a valid value.
  void checkParams(const MethodParams& params) const;
  // A parameter's value: the settings' text, else its default; parsed as a number (Double, Int, Bool)
  // or returned as text (Choice). Throws std::invalid_argument if `name` is not one of params().
  double param(const RenderSettings& settings, const std::string& name) const;
  std::string paramText(const RenderSettings& settings, const std::string& name) const;
};

}  // namespace mlt
