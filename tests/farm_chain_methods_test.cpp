// The newer chain methods on the farm (issues 11 and 12): rjmlt and veach-mlt rendered by a coordinator and
// two workers (in this process, over gRPC on loopback) give the same pixels, bit for bit, as
// `mltfarm render --in-process` with the same settings and seed, and the EXR carries the same chain
// statistics: per mutation kind (rjmlt: large, small, technique; veach-mlt: its five moves) the proposals
// and acceptance, per path length the mutations and acceptance (rjmlt), and b. Those travel from the
// workers as ChainStats (proto/convert.cpp) and are merged by the coordinator: a farm that dropped or
// mis-merged them would write other numbers than the in-process render. The wall time per move kind
// (issue 12) travels with every task (the partial films the coordinator keeps) and stays out of the
// farm's image, whose bytes must not depend on the run; the in-process image has it (NAMESeconds).
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "common/io/exr_io.h"
#include "common/methods/image_metadata.h"
#include "common/methods/registry.h"
#include "coordinator/merge.h"
#include "tests/farm/farm_harness.h"
#include "tests/farm/in_process_farm.h"

namespace mlt::farm::test {
namespace {

// Keys of the developed image that only the farm writes (its job id, task count, wire version).
bool farmOnlyKey(const std::string& key) { return key.rfind("farm.", 0) == 0; }

struct Rendered {
  ExrImage farm;
  std::vector<PartialExr> partials;  // the tasks' partial films as the coordinator stored them
  cli::LocalRenderResult local;
  uint64_t tasksOfWorker[2] = {0, 0};
};

Rendered renderBothWays(const std::string& scene, const std::string& args, const std::string& name) {
  const cli::CommandLineSettings cl = parseRenderSettings(args);
  WorkerOptions wo;
  wo.threads = 1;
  wo.taskDelayMs = 10;  // each worker holds a lease a moment, so that both of them get tasks
  CoordinatorOptions co;
  co.keepPartials = true;
  InProcessFarm farm(2, wo, co);
  Rendered r;
  r.farm = readExr(farm.render(scene, cl, name + ".exr"));
  farm.stop();
  for (const auto& e : std::filesystem::directory_iterator(farm.stateDir() + "/jobs/job-1/partials"))
    r.partials.push_back(readPartialExr(e.path().string()));
  for (int i = 0; i < 2; ++i) r.tasksOfWorker[i] = uint64_t(farm.worker(size_t(i)).metrics().tasksUploaded.Value());
  r.local = renderInProcess(scene, cl);
  return r;
}

double number(const ExrImage& image, const std::string& key) {
  const auto it = image.metadata.numbers.find(key);
  if (it == image.metadata.numbers.end()) ADD_FAILURE() << "the farm's image has no " << key;
  return it == image.metadata.numbers.end() ? -1 : it->second;
}

std::string text(const ExrImage& image, const std::string& key) {
  const auto it = image.metadata.strings.find(key);
  if (it == image.metadata.strings.end()) ADD_FAILURE() << "the farm's image has no " << key;
  return it == image.metadata.strings.end() ? "" : it->second;
}

// Pixels bit-identical; the farm's image has, apart from its own farm.* keys, exactly the numeric keys that
// the in-process render derives from its plan and merged result (image_metadata.h: not its wall-clock
// keys), with the same values.
void expectSameImageAndStatistics(const Rendered& r, const std::string& method) {
  EXPECT_GT(r.tasksOfWorker[0], 0u) << method << ": the first worker ran no task";
  EXPECT_GT(r.tasksOfWorker[1], 0u) << method << ": the second worker ran no task";
  ASSERT_EQ(r.farm.width, r.local.plan.settings.width);
  ASSERT_EQ(r.farm.height, r.local.plan.settings.height);
  ASSERT_EQ(r.farm.rgb.size(), r.local.image.size());
  EXPECT_EQ(std::memcmp(r.farm.rgb.data(), r.local.image.data(), r.local.image.size() * sizeof(Color)), 0)
      << method << ": the farm's pixels differ from the in-process render's";
  double sum = 0;
  for (const Color& c : r.local.image) sum += c.r + c.g + c.b;
  EXPECT_GT(sum, 0.0) << method;
  const ImageMetadata local = imageMetadata(r.local.plan, r.local.merged, "", r.local.sceneHash);
  for (const char* key : {"method", "mutationKinds", "sceneHash", "seed"})
    EXPECT_EQ(text(r.farm, key), local.strings.at(key)) << method << ": " << key;
  for (const auto& [key, value] : local.numbers) EXPECT_EQ(number(r.farm, key), value) << method << ": " << key;
  for (const auto& [key, value] : r.farm.metadata.numbers)
    EXPECT_TRUE(farmOnlyKey(key) || local.numbers.count(key)) << method << ": the farm's image has " << key
                                                              << ", the in-process one not";
  // The workers' wall time per move kind (issue 12) came with every task; the image has none of it.
  const std::vector<std::string>& kinds = mutationKindNames(method);
  ASSERT_FALSE(r.partials.empty());
  std::vector<double> proposed(kinds.size(), 0.0);
  for (const PartialExr& p : r.partials) {
    const ChainStats& st = p.result.stats;
    if (p.result.samples == 0 && st.proposedPerKind.empty()) continue;  // only direct-pass units (separateDirect)
    ASSERT_EQ(st.secondsPerKind.size(), kinds.size()) << method << ", task " << p.task;
    for (size_t k = 0; k < kinds.size(); ++k) {
      EXPECT_EQ(st.secondsPerKind[k] > 0, st.proposedPerKind[k] > 0) << method << ", task " << p.task << ": " << kinds[k];
      proposed[k] += double(st.proposedPerKind[k]);
    }
  }
  for (size_t k = 0; k < kinds.size(); ++k) {
    EXPECT_EQ(number(r.farm, kinds[k] + "Steps"), proposed[k]) << method << ": " << kinds[k];
    EXPECT_EQ(r.farm.metadata.numbers.count(kinds[k] + "Seconds"), 0u) << method << ": " << kinds[k];
    if (proposed[k] > 0) EXPECT_GT(r.local.metadata.numbers.at(kinds[k] + "Seconds"), 0.0) << method << ": " << kinds[k];
  }
}

// The keys of one mutation kind (chain_report.h): NAMESteps (proposals) and acceptanceNAME.
double steps(const ExrImage& image, const std::string& kind) { return number(image, kind + "Steps"); }
double acceptance(const ExrImage& image, std::string kind) {
  kind[0] = char(std::toupper(kind[0]));
  return number(image, "acceptance" + kind);
}

TEST(FarmChainMethods, RjmltOnTwoWorkersMatchesTheInProcessRenderAndCarriesItsMoveStatistics) {
  // Technique changes more often than the default 5 %, so that they are many even in a small job.
  const Rendered r = renderBothWays(cornellBox(),
                                    "--method rjmlt --seed 7 --width 32 --height 32 --mutations-per-pixel 8 --chains 24 "
                                    "--bootstrap 4000 --max-depth 4 --large-step 0.1 --technique-step 0.2 --direct-light chains",
                                    "rjmlt");
  expectSameImageAndStatistics(r, "rjmlt");
  const ExrImage& img = r.farm;
  EXPECT_EQ(text(img, "mutationKinds"), "large,small,technique");
  const double mutations = number(img, "mutations");
  EXPECT_EQ(mutations, 32.0 * 32 * 8);
  // Every kind proposed about as often as its probability says, and accepted sometimes.
  EXPECT_EQ(steps(img, "large") + steps(img, "small") + steps(img, "technique"), mutations);
  EXPECT_NEAR(steps(img, "technique") / mutations, 0.2, 0.03);
  EXPECT_NEAR(steps(img, "large") / mutations, 0.1, 0.03);
  for (const char* kind : {"large", "small", "technique"}) {
    EXPECT_GT(acceptance(img, kind), 0.0) << kind;
    EXPECT_LE(acceptance(img, kind), 1.0) << kind;
  }
  // Per path length k (chains per length, as mmlt): chains, mutations and acceptance for k = 1..4.
  double perLength = 0, chains = 0;
  for (int k = 1; k <= 4; ++k) {
    const std::string ks = std::to_string(k);
    chains += number(img, "chains" + ks);
    perLength += number(img, "mutations" + ks);
    if (number(img, "mutations" + ks) > 0) EXPECT_GT(number(img, "acceptance" + ks), 0.0) << "k = " << k;
  }
  EXPECT_EQ(chains, 24);
  EXPECT_EQ(perLength, mutations);
}

TEST(FarmChainMethods, VeachMltOnTwoWorkersMatchesTheInProcessRenderAndCarriesItsMoveStatistics) {
  // Two scenes, so that each of the six moves has paths to work on: the Cornell box (all diffuse: the
  // caustic perturbation applies, the multi-chain one does not) and the caustic scene (every camera ray
  // hits a mirror first: no D E end for the caustic perturbation, specular chains for the multi-chain one).
  // The deep lens perturbation, off by default, is switched on.
  const std::vector<std::string> kinds = {"bidir", "lens", "caustic", "multichain", "lens-subpath", "deep-lens"};
  std::map<std::string, double> proposedSomewhere;
  for (const std::string scene : {"cornell-box", "caustic-mirror"}) {
    const Rendered r = renderBothWays(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + scene + ".xml",
                                      "--method veach-mlt --seed 7 --width 32 --height 32 --mutations-per-pixel 8 "
                                      "--chains 24 --bootstrap 4000 --max-depth 5 --veach-deep-lens 1",
                                      "veach-" + scene);
    expectSameImageAndStatistics(r, "veach-mlt");
    const ExrImage& img = r.farm;
    EXPECT_EQ(text(img, "mutationKinds"), "bidir,lens,caustic,multichain,lens-subpath,deep-lens");
    const double mutations = number(img, "mutations");
    EXPECT_EQ(mutations, 32.0 * 32 * 8) << scene;
    double proposed = 0;
    for (const std::string& kind : kinds) {
      EXPECT_GE(steps(img, kind), 0.0) << scene << ": no " << kind << "Steps";
      EXPECT_GE(acceptance(img, kind), 0.0) << scene << ": no acceptance of " << kind;
      EXPECT_LE(acceptance(img, kind), 1.0) << scene << ": " << kind;
      if (steps(img, kind) > 0) EXPECT_GT(acceptance(img, kind), 0.0) << scene << ": " << kind;
      proposed += steps(img, kind);
      proposedSomewhere[kind] += steps(img, kind);
    }
    EXPECT_EQ(proposed, mutations) << scene;
    EXPECT_GT(steps(img, "bidir"), 0.0) << scene;
    EXPECT_GT(steps(img, "lens-subpath"), 0.0) << scene;
  }
  for (const std::string& kind : kinds) EXPECT_GT(proposedSomewhere[kind], 0.0) << kind << " never proposed";
}

// With the direct light rendered separately (issue 12): the chains and the pt direct pass's batches run
// on the workers, and the image is the in-process one, bit for bit, its metadata saying separateDirect.
TEST(FarmChainMethods, VeachMltWithSeparateDirectOnTwoWorkersMatchesTheInProcessRender) {
  const Rendered r = renderBothWays(std::string(MLTFARM_SOURCE_DIR) + "/scenes/caustic-mirror.xml",
                                    "--method veach-mlt --separate-direct --spp 4 --seed 7 --width 32 --height 32 "
                                    "--mutations-per-pixel 8 --chains 24 --bootstrap 4000 --max-depth 5",
                                    "veach-separate-direct");
  expectSameImageAndStatistics(r, "veach-mlt");
  EXPECT_EQ(number(r.farm, "separateDirect"), 1.0);
  EXPECT_EQ(number(r.farm, "mutations"), 32.0 * 32 * 8);
  EXPECT_GT(r.local.plan.units.size(), size_t(r.local.plan.settings.chains)) << "no direct-pass units";
}

// The lights seen directly by a pass of their own (--direct-light auto's choice on glossy-plates, whose
// spheres are small on the film): its stratified, multiplied pixel samples run on the workers as the
// direct pass's batches, and the image is the in-process one, bit for bit, its metadata naming the choice.
TEST(FarmChainMethods, MmltWithTheEmissionPassOnTwoWorkersMatchesTheInProcessRender) {
  const Rendered r = renderBothWays(std::string(MLTFARM_SOURCE_DIR) + "/scenes/glossy-plates.xml",
                                    "--method mmlt --seed 7 --width 64 --height 64 --mutations-per-pixel 8 --chains 24 "
                                    "--bootstrap 4000",
                                    "mmlt-emission");
  expectSameImageAndStatistics(r, "mmlt");
  EXPECT_EQ(text(r.farm, "directLight"), "emission");
  EXPECT_EQ(number(r.farm, "separateDirect"), 0.0);
  EXPECT_GT(r.local.plan.units.size(), size_t(r.local.plan.settings.chains)) << "no units of the pass";
}

// A shaped target: the relative one (common/mlt/importance.h: the coordinator's plan carries the importance
// map to the workers and their chains' target reads it) and a tempered one (common/mlt/target.h (T1): the
// plan carries the power). Either way the plan carries b_lum's bootstrap estimate, the partials carry the
// large steps' luminance sums, and the merged image is scaled to b_lum (develop.h (D8)): the in-process
// image, bit for bit, with the same b.
TEST(FarmChainMethods, MmltWithAShapedTargetOnTwoWorkersMatchesTheInProcessRender) {
  struct Shape {
    const char* options;
    const char* target;
    bool map;
    double power;
  };
  for (const Shape& shape : {Shape{"--target relative", "relative", true, 1.0},
                             Shape{"--target-power 0.7", "luminance", false, 0.7}}) {
    SCOPED_TRACE(shape.options);
    const Rendered r = renderBothWays(std::string(MLTFARM_SOURCE_DIR) + "/scenes/cornell-box.xml",
                                      std::string("--method mmlt ") + shape.options +
                                          " --seed 7 --width 32 --height 32 --mutations-per-pixel 8 --chains 24 "
                                          "--bootstrap 4000",
                                      std::string("mmlt-") + shape.target);
    expectSameImageAndStatistics(r, "mmlt");
    EXPECT_EQ(text(r.farm, "target"), shape.target);
    if (shape.map) EXPECT_EQ(number(r.farm, "targetFloor"), 0.5);
    if (shape.power != 1) EXPECT_EQ(number(r.farm, "targetPower"), shape.power);
    EXPECT_EQ(r.local.plan.norm.importance.empty(), !shape.map);
    EXPECT_EQ(r.local.plan.norm.targetPower, shape.power);
    EXPECT_FALSE(r.local.plan.norm.bootstrapLuminance.empty());
  }
}

// Rao-Blackwellized b samples (--b-sample-every, develop.h (D9)): the workers draw them beside their chains
// and send their sums where the large steps' go; the plan holds no bootstrap estimate for those lengths. The
// farm's image is the in-process one, bit for bit, with the same b and the stride in its metadata.
TEST(FarmChainMethods, MmltWithBSamplesOnTwoWorkersMatchesTheInProcessRender) {
  const Rendered r = renderBothWays(std::string(MLTFARM_SOURCE_DIR) + "/scenes/cornell-box.xml",
                                    "--method mmlt --b-sample-every 4 --seed 7 --width 32 --height 32 "
                                    "--mutations-per-pixel 8 --chains 24 --bootstrap 4000 --direct-light chains",
                                    "mmlt-b-samples");
  expectSameImageAndStatistics(r, "mmlt");
  EXPECT_EQ(number(r.farm, "bSampleEvery"), 4.0);
  uint64_t expected = r.local.plan.norm.bootstrapSamplesInB;  // length 1's candidates (or none: camera rays)
  for (const WorkUnit& u : r.local.plan.units)
    if (u.pathLength >= 2) expected += (u.mutations + 3) / 4;
  const ChainStats& st = r.local.merged.stats;
  if (st.largeStepSums.size() > 1) expected += st.largeStepSums[1].n;  // length 1 keeps its large steps
  EXPECT_EQ(number(r.farm, "bSamples"), double(expected));
}

}  // namespace
}  // namespace mlt::farm::test
