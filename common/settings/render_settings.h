// The settings of a render job, below every layer that uses them (integrators, chains, jobs, methods,
// the wire). A method is named by a string and looked up in the registry (common/methods/registry.h);
// nothing below the methods layer knows which methods exist.
//
// Settings come in groups, and each method reads only its own (the wire carries them as a oneof,
// proto/mltfarm.proto):
//   - common: method, seed, film size, integrator (max depth, Russian roulette, MIS heuristic);
//   - sample batches (family Samples: pt, lt, bdpt; also the direct pass of a chain method with
//     directLight Separate): spp, samplesPerUnit;
//   - Markov chains (family MarkovChain): mutations, chains, bootstrap, the Kelemen sample source's kernel,
//     splatting, directLight;
//   - `params`: a method's own named parameters (e.g. a mutation's probability), declared by the method
//     (RenderMethod::params) with their defaults, parsed and validated by it. A new method adds
//     parameters here without touching the wire, the CLI parser or this file.
#pragma once
#include <cstdint>
#include <map>
#include <string>

namespace mlt {

enum class MisHeuristic { Balance, Power };

struct IntegratorSettings {
  int maxDepth = 5;           // maximum number of path segments (edges); -1 = unlimited
  int rrDepth = 5;            // Russian roulette starts after this many segments
  MisHeuristic heuristic = MisHeuristic::Power;
  bool operator==(const IntegratorSettings&) const = default;
};

enum class MutationKernel { Kelemen, Gaussian };  // Kelemen 2002 exponential (s1, s2) or Gaussian (sigma)
// MethodDefault: the method's (ChainJobSpec::defaultSplatting: Kelemen MIS; veach-mlt expected values),
// resolved when the job is planned, and the plan holds the value used.
enum class MltSplatting { MethodDefault, ExpectedValue, KelemenMIS };
// How a chain method renders paths of at most two segments (the direct light): Auto, the plan decides
// from a pilot (common/job/direct_light_rule.h) and holds the value used; Chains, the chains carry them
// with the rest; Separate, a pt pass renders them (kDirectPassMethod) and the chains carry only longer paths;
// Emission (mmlt, rjmlt, pssmlt-bdpt), a pt pass renders the lights seen directly (paths of one segment) and the chains
// every longer path (mlt_job.h, kEmissionSppPerMutation: why).
enum class DirectLight { Auto, Chains, Separate, Emission };

// A method's own parameters: name -> value as text (the method's ParamSpec says how to read it).
using MethodParams = std::map<std::string, std::string>;

struct RenderSettings {
  std::string method = "bdpt";                    // a registered method's name (common/methods/registry.h)
  uint64_t seed = 1;
  int width = 0, height = 0;                      // 0 = the scene's film size
  IntegratorSettings integrator;                  // maxDepth counts path segments
  // Sample batches (pt, lt, bdpt; the direct pass of directLight Separate).
  int spp = 16;                                   // samples per pixel (lt: light paths = spp * pixels)
  int samplesPerUnit = 0;                         // spp per work unit; 0 = choose automatically
  // Markov chain methods.
  double mutationsPerPixel = 16;
  int chains = 0;                                 // 0 = choose automatically
  // Bootstrap candidates per path length; 0 = automatic (a few percent of the mutations, see mlt_job.h).
  // The bootstrap only finds start states and allocates chains to lengths: b is refined by the chains'
  // large steps (mlt/develop.h (D3)).
  int bootstrapSamples = 0;
  // Large-step probability; negative (kMethodDefaultLargeStep): the method's default, resolved when the job
  // is planned (ChainJobSpec::defaultLargeStepProb: 0.3; rjmlt 0.1), and the plan holds the value used.
  float largeStepProb = -1.0f;
  MutationKernel kernel = MutationKernel::Kelemen;
  float kelemenS1 = 1.0f / 1024, kelemenS2 = 1.0f / 64, gaussianSigma = 0.01f;
  MltSplatting splatting = MltSplatting::MethodDefault;
  DirectLight directLight = DirectLight::Auto;    // Separate: direct light by pt, chains do indirect only
  MethodParams params;                            // the method's own parameters (validated by the method)
  double timeBudgetSeconds = 0;                   // 0 = no time budget (local renderer only)
};

// Whether the job renders its shortest paths by a pass of its own (a planned job's settings hold Chains,
// Separate or Emission; Auto, not yet decided, counts as no pass).
inline bool separatesDirect(const RenderSettings& s) {
  return s.directLight == DirectLight::Separate || s.directLight == DirectLight::Emission;
}
// The longest paths (in segments) the pass renders: 2 (Separate: emission seen directly and one bounce),
// 1 (Emission), 0 (no pass). The chains carry the longer ones.
inline int directPassSegments(const RenderSettings& s) {
  return s.directLight == DirectLight::Separate ? 2 : s.directLight == DirectLight::Emission ? 1 : 0;
}

// Whether spp comes from the scene's sampler sample_count (when it has one): only when the user gave no
// spp, renders by samples (a time budget sizes the job itself) and asks for no direct pass (its spp is
// the pass's, sized by the plan, directSppFor; sample_count is meant for pt and bdpt; an automatic pass
// sizes its own spp). The one rule for the
// in-process renderer and the coordinator.
inline bool takesSceneSampleCount(const RenderSettings& s, bool sppGiven) {
  return !sppGiven && s.timeBudgetSeconds <= 0 && !separatesDirect(s);
}

}  // namespace mlt
