// A render job as the farm sees it, independent of the method: settings -> plan (bootstrap, work units)
// -> partial results of work units -> one developed image. The local CLI, the coordinator and the worker
// all call exactly these functions, so an image rendered through the farm is the one rendered locally.
//
//   JobPlan plan = planJob(scene, settings);            // coordinator: bootstrap for MLT methods
//   PartialResult r = runWorkUnit(scene, plan, unit);   // worker: a chain, or a batch of pixel samples
//   merged.add(r) for units in index order;              // coordinator or `mltfarm merge`
//   std::vector<Color> img = developImage(plan, merged); // normalization applied once, here
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/film/film.h"
#include "common/integrators/path_evaluator.h"
#include "common/mlt/target_sums.h"

namespace mlt {

class RenderScene;

enum class Method { PT, LT, BDPT, PSSMLT, PSSMLT_BDPT, MMLT };
const char* methodName(Method m);                 // "pt", "lt", "bdpt", "pssmlt", "pssmlt-bdpt", "mmlt"
Method parseMethod(const std::string& name);      // throws std::invalid_argument naming the value
bool isMarkovChainMethod(Method m);
// The names of a Markov chain method's mutation kinds, index = Proposal::kind (pssmlt, pssmlt-bdpt,
// mmlt: "large", "small"); empty for the others. Statistics and metadata keys use these names.
const std::vector<std::string>& mutationKindNames(Method m);

enum class MutationKernel { Kelemen, Gaussian };  // Kelemen 2002 exponential (s1, s2) or Gaussian (sigma)
enum class MltSplatting { ExpectedValue, KelemenMIS };

struct RenderSettings {
  Method method = Method::BDPT;
  uint64_t seed = 1;
  int width = 0, height = 0;                      // 0 = the scene's film size
  IntegratorSettings integrator;                  // maxDepth counts path segments
  // Sample-based methods (pt, lt, bdpt).
  int spp = 16;                                   // samples per pixel (lt: light paths = spp * pixels)
  int samplesPerUnit = 0;                         // spp per work unit; 0 = choose automatically
  // Markov chain methods.
  double mutationsPerPixel = 16;
  int chains = 0;                                 // 0 = choose automatically
  // Bootstrap candidates per path length; 0 = automatic (a few percent of the mutations, see mlt_job.h).
  // The bootstrap only finds start states and allocates chains to lengths: b is refined by the chains'
  // large steps (mlt/develop.h (D3)).
  int bootstrapSamples = 0;
  float largeStepProb = 0.3f;
  MutationKernel kernel = MutationKernel::Kelemen;
  float kelemenS1 = 1.0f / 1024, kelemenS2 = 1.0f / 64, gaussianSigma = 0.01f;
  MltSplatting splatting = MltSplatting::ExpectedValue;
  bool separateDirect = false;                    // render direct light by bdpt; chains do indirect only
  double timeBudgetSeconds = 0;                   // 0 = no time budget (local renderer only)
};

// One independent piece of work: a Markov chain or a batch of pixel samples. Small and serializable.
struct WorkUnit {
  uint32_t index = 0;            // chain index / batch index; results are merged in this order
  // Sample batch: samples [sampleBegin, sampleEnd) of every pixel (lt: light paths in that range).
  uint32_t sampleBegin = 0, sampleEnd = 0;
  // Markov chain.
  uint64_t startCandidate = 0;   // bootstrap candidate index the chain starts from
  int pathLength = -1;           // mmlt: path length k (segments); -1 otherwise
  uint64_t mutations = 0;
  double startContribution = 0;  // c(x0) recorded by the bootstrap; the worker's replay must reproduce it
};

// Normalization inputs decided by the plan, needed both by chains and by development.
struct Normalization {
  // The bootstrap's estimates: they allocate chains to lengths and weight Kelemen MIS splats. The image
  // is developed with b pooled from these sums and the chains' large steps (mlt/develop.h (D3)).
  double b = 0, bStdErr = 0;                 // mean target value c over the bootstrap (all lengths)
  std::vector<double> bk, bkStdErr;          // mmlt: per path length k (index = k)
  std::vector<BootstrapEstimate> bootstrapB; // per path length slot (pssmlt: 0; mmlt: k)
  std::vector<uint64_t> mutationsPerLength;  // mmlt: total planned mutations per length
  uint64_t totalMutations = 0;
  uint64_t bootstrapSamples = 0;
  double bootstrapSeconds = 0;
};

struct JobPlan {
  RenderSettings settings;       // with width/height/chains/samplesPerUnit resolved
  Normalization norm;
  std::vector<WorkUnit> units;
};

struct ChainStats {              // sums, so they merge by addition
  std::vector<uint64_t> proposedPerLength, acceptedPerLength;  // index = path length (pssmlt: index 0)
  std::vector<uint64_t> proposedPerKind, acceptedPerKind;  // index = mutation kind (mutationKindNames)
  std::vector<TargetSums> largeStepSums;     // c of every large step, per path length slot (quantized per unit)
  void add(const ChainStats& o);
};

struct PartialResult {
  Film film;                     // raw sums
  uint64_t samples = 0;          // pixel samples (sample methods) or mutations (chains) it holds
  ChainStats stats;
  std::vector<uint32_t> units;   // work unit indices included (sorted)
  double seconds = 0;            // wall time spent (informational; never affects the image)
  // Element-wise sum. Callers add in unit-index order for bit-identical results.
  void add(const PartialResult& o);
};

JobPlan planJob(const RenderScene& scene, const RenderSettings& settings);
PartialResult runWorkUnit(const RenderScene& scene, const JobPlan& plan, const WorkUnit& unit);
// Linear RGB, row-major from the top-left. All normalization happens here.
std::vector<Color> developImage(const JobPlan& plan, const PartialResult& merged);

}  // namespace mlt
