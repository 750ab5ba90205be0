// The Markov-chain job API on a small Cornell box: determinism (same unit -> identical partial result;
// the plan is independent of the thread count), exact merging (any grouping of units develops to the same
// bytes), the loud replay check, chain allocation, and normalization (K chains of M mutations vs one
// chain of K*M agree within the spread of independent runs).
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <vector>

#include "common/job/mlt_job.h"
#include "common/methods/pss_method.h"
#include "common/methods/registry.h"
#include "common/methods/chain_report.h"
#include "common/render/render_scene.h"
#include "common/scene/scene_loader.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(16, 12));
  return *scene;
}

RenderSettings settingsFor(std::string m, uint64_t seed) {
  RenderSettings s;
  s.directLight = DirectLight::Chains;  // chains over every length (the automatic choice: direct_light_rule_test)
  s.method = m;
  s.seed = seed;
  s.integrator.maxDepth = 4;
  s.mutationsPerPixel = 8;
  s.bootstrapSamples = 4000;
  s.chains = 12;
  return s;
}

std::vector<PartialResult> runAll(const RenderScene& scene, const JobPlan& plan) {
  std::vector<PartialResult> results(plan.units.size());
  tbb::parallel_for(size_t(0), plan.units.size(), [&](size_t i) { results[i] = runWorkUnit(scene, plan, plan.units[i]); });
  return results;
}

bool sameBytes(const std::vector<Color>& a, const std::vector<Color>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Color)) == 0;
}

bool sameFilm(const Film& a, const Film& b) {
  if (a.splatLayerCount() != b.splatLayerCount()) return false;
  for (size_t l = 0; l < a.splatLayerCount(); ++l) {  // every splat layer (a chain job: one per path length)
    if (a.hasSplatLayer(l) != b.hasSplatLayer(l)) return false;
    if (a.hasSplatLayer(l) &&
        std::memcmp(a.splatLayer(l).data(), b.splatLayer(l).data(), a.splatLayer(l).size() * sizeof(RGBd)) != 0)
      return false;
  }
  return a.pixelSums().size() == b.pixelSums().size() &&
         std::memcmp(a.pixelSums().data(), b.pixelSums().data(), a.pixelSums().size() * sizeof(RGBd)) == 0 &&
         a.pixelCounts() == b.pixelCounts();
}

const std::string kMethods[] = {"pssmlt", "pssmlt-bdpt", "mmlt"};

TEST(MltJob, SameUnitGivesIdenticalPartialResult) {
  for (std::string m : kMethods) {
    const JobPlan plan = planJob(cornell(), settingsFor(m, 3));
    ASSERT_FALSE(plan.units.empty());
    for (size_t i : {size_t(0), plan.units.size() - 1}) {
      PartialResult a = runWorkUnit(cornell(), plan, plan.units[i]);
      PartialResult b = runWorkUnit(cornell(), plan, plan.units[i]);
      a.foldSplats();  // a chain unit's splats travel sparse (common/film/sparse_splats.h)
      b.foldSplats();
      ASSERT_EQ(a.film.width(), plan.settings.width);
      EXPECT_TRUE(sameFilm(a.film, b.film)) << m.c_str() << " unit " << i;
      EXPECT_EQ(a.samples, plan.units[i].mutations);
      EXPECT_EQ(a.stats.acceptedPerKind, b.stats.acceptedPerKind);
      ASSERT_EQ(a.stats.proposedPerKind.size(), mutationKindNames(m).size());
      EXPECT_EQ(a.stats.proposedPerKind[0] + a.stats.proposedPerKind[1], plan.units[i].mutations);
    }
  }
}

TEST(MltJob, PlanIsIndependentOfThreadCount) {
  for (std::string m : kMethods) {
    JobPlan a, b;
    {
      tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      a = planJob(cornell(), settingsFor(m, 5));
    }
    b = planJob(cornell(), settingsFor(m, 5));
    EXPECT_EQ(std::memcmp(&a.norm.b, &b.norm.b, sizeof(double)), 0) << m.c_str();
    EXPECT_EQ(a.norm.bk, b.norm.bk);
    ASSERT_EQ(a.units.size(), b.units.size());
    for (size_t i = 0; i < a.units.size(); ++i) {
      EXPECT_EQ(a.units[i].startCandidate, b.units[i].startCandidate);
      EXPECT_EQ(a.units[i].mutations, b.units[i].mutations);
      EXPECT_EQ(a.units[i].pathLength, b.units[i].pathLength);
    }
  }
}

TEST(MltJob, AnyGroupingOfUnitsDevelopsToIdenticalBytes) {
  for (std::string m : kMethods) {
    RenderSettings s = settingsFor(m, 7);
    s.mutationsPerPixel = 200;  // many splats per pixel: sums whose rounding depends on the grouping
    if (m == "mmlt") s.directLight = DirectLight::Separate;  // include direct-pass units in the merge
    const JobPlan plan = planJob(cornell(), s);
    const std::vector<PartialResult> parts = runAll(cornell(), plan);
    PartialResult sequential;
    for (const PartialResult& p : parts) sequential.add(p);
    // Groups of 3 (as a worker might return them), then the groups in order; and pairs in reverse order.
    PartialResult grouped;
    for (size_t g = 0; g < parts.size(); g += 3) {
      PartialResult group;
      for (size_t i = g; i < std::min(parts.size(), g + 3); ++i) group.add(parts[i]);
      grouped.add(group);
    }
    PartialResult reversed;
    for (size_t i = parts.size(); i-- > 0;) reversed.add(parts[i]);
    const std::vector<Color> a = developImage(plan, sequential);
    EXPECT_TRUE(sameBytes(a, developImage(plan, grouped))) << m.c_str();
    EXPECT_TRUE(sameBytes(a, developImage(plan, reversed))) << m.c_str();
    // Stronger: the merged double sums themselves (what a partial EXR stores) are identical.
    EXPECT_TRUE(sameFilm(sequential.film, grouped.film)) << m.c_str();
    EXPECT_TRUE(sameFilm(sequential.film, reversed.film)) << m.c_str();
  }
}

// The splatting a job leaves to its method: Kelemen MIS for the primary-sample chains, whose large steps'
// share goes to its own layer per path length slot (develop.h (D7)); expected values for veach-mlt, which
// has no large steps and refuses Kelemen MIS by name. Expected values keep no such layer.
TEST(MltJob, SplattingIsTheMethodsUnlessGiven) {
  for (const std::string m : {"pssmlt", "pssmlt-bdpt", "mmlt", "rjmlt"}) {
    RenderSettings s = settingsFor(m, 3);
    ASSERT_EQ(s.splatting, MltSplatting::MethodDefault);
    const JobPlan plan = planJob(cornell(), s);
    EXPECT_EQ(plan.settings.splatting, MltSplatting::KelemenMIS) << m;
    const size_t slots = plan.norm.mutationsPerLength.size();
    const std::vector<PartialResult> parts = runAll(cornell(), plan);
    PartialResult merged;
    for (const PartialResult& p : parts) merged.add(p);
    for (size_t slot = 0; slot < slots; ++slot)
      EXPECT_EQ(merged.film.hasSplatLayer(largeStepLayer(slot, slots)), plan.norm.mutationsPerLength[slot] > 0)
          << m << " slot " << slot;
    s.splatting = MltSplatting::ExpectedValue;
    const JobPlan ev = planJob(cornell(), s);
    PartialResult evMerged;
    for (const PartialResult& p : runAll(cornell(), ev)) evMerged.add(p);
    EXPECT_LE(evMerged.film.splatLayerCount(), largeStepLayer(0, slots)) << m << ": expected values keep no large-step layer";
  }
  RenderSettings v = settingsFor("veach-mlt", 3);
  EXPECT_EQ(planJob(cornell(), v).settings.splatting, MltSplatting::ExpectedValue);
  v.splatting = MltSplatting::KelemenMIS;
  try {
    planJob(cornell(), v);
    ADD_FAILURE() << "veach-mlt planned a job with Kelemen MIS splatting";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("kelemen-mis"), std::string::npos) << e.what();
  }
}

// separateDirect without spp (spp = 0): the plan sizes the direct pass from the mutations per pixel and the
// pilot's share (run for the size alone when the pass was asked for), and the plan is the one an explicit
// spp of that size gives, unit for unit and pixel for pixel. The plan records the resolved spp (an EXR's
// metadata reproduces the job); a negative spp is refused.
TEST(MltJob, DirectPassWithoutSppIsSizedByTheMutations) {
  EXPECT_EQ(directSppFor(0.5, 8), 4);
  EXPECT_EQ(directSppFor(0.5, 0.01), 1);
  EXPECT_EQ(directSppFor(0.47, 100), 47);
  EXPECT_EQ(directSppFor(0.471, 100), 48);  // rounded up
  for (double mpp : {8.0, 30.0}) {
    RenderSettings s = settingsFor("mmlt", 3);
    s.directLight = DirectLight::Separate;
    s.mutationsPerPixel = mpp;
    s.spp = 0;
    const JobPlan automatic = planJob(cornell(), s);
    const DirectLightPilot pilot = directLightPilot(cornell(), automatic.settings);  // the film resolved
    const int spp = directSppFor(directSppPerMutation(*findChainJobSpec("mmlt"), s, &pilot), mpp);
    EXPECT_EQ(automatic.settings.spp, spp);
    EXPECT_LT(automatic.norm.directShare, 0);  // asked for, not the pilot's choice: no share recorded
    s.spp = spp;
    const JobPlan given = planJob(cornell(), s);
    ASSERT_EQ(automatic.units.size(), given.units.size());
    size_t direct = 0;
    for (size_t i = 0; i < given.units.size(); ++i) {
      const WorkUnit &a = automatic.units[i], &b = given.units[i];
      direct += isDirectUnit(b) ? 1 : 0;
      EXPECT_EQ(a.sampleBegin, b.sampleBegin);
      EXPECT_EQ(a.sampleEnd, b.sampleEnd);
      EXPECT_EQ(a.mutations, b.mutations);
      EXPECT_EQ(a.startCandidate, b.startCandidate);
    }
    EXPECT_GT(direct, 0u);
    PartialResult ra, rb;
    for (const PartialResult& p : runAll(cornell(), automatic)) ra.add(p);
    for (const PartialResult& p : runAll(cornell(), given)) rb.add(p);
    EXPECT_TRUE(sameBytes(developImage(automatic, ra), developImage(given, rb))) << mpp;
  }
  RenderSettings bad = settingsFor("mmlt", 3);
  bad.directLight = DirectLight::Separate;
  bad.spp = -1;
  EXPECT_THROW(planJob(cornell(), bad), std::invalid_argument);
}

// The pass's samples per mutation per pixel (mlt_job.h, directSppPerMutation): in proportion to the odds
// s / (1 - s) of the pilot's share s of the light in the pass's paths, capped at kDirectMaxShareOdds, and to
// the method's mutation cost; without a pilot, kDirectSppPerMutation times that cost.
TEST(MltJob, DirectPassSizeFollowsTheShareOfTheLightItRenders) {
  const ChainJobSpec& mmlt = *findChainJobSpec("mmlt");
  const ChainJobSpec& bidir = *findChainJobSpec("pssmlt-bdpt");
  RenderSettings separate;
  separate.directLight = DirectLight::Separate;
  DirectLightPilot p;
  p.share = 0.8;  // odds 4
  EXPECT_NEAR(directSppPerMutation(mmlt, separate, &p), 4 * kDirectSppPerShareOdds, 1e-12);
  p.share = 0.9;  // odds 9: a scene whose chains carry half the light of the one above gets ~2.25x the pass
  EXPECT_NEAR(directSppPerMutation(mmlt, separate, &p), 9 * kDirectSppPerShareOdds, 1e-9);
  EXPECT_NEAR(directSppPerMutation(bidir, separate, &p), bidir.mutationCost() * 9 * kDirectSppPerShareOdds, 1e-9);
  for (double share : {0.96, 0.999, 1.0}) {
    p.share = share;
    EXPECT_EQ(directSppPerMutation(mmlt, separate, &p), kDirectMaxShareOdds * kDirectSppPerShareOdds) << share;
  }
  p.share = 0;
  EXPECT_EQ(directSppPerMutation(mmlt, separate, &p), 0.0);  // still at least one sample per pixel (directSppFor)
  EXPECT_EQ(directSppFor(directSppPerMutation(mmlt, separate, &p), 10), 1);
  EXPECT_EQ(directSppPerMutation(mmlt, separate, nullptr), kDirectSppPerMutation);
  EXPECT_EQ(directSppPerMutation(bidir, separate, nullptr), bidir.mutationCost() * kDirectSppPerMutation);
  EXPECT_GT(bidir.mutationCost(), 1.0);  // a whole bdpt sample per mutation
  EXPECT_EQ(findChainJobSpec("rjmlt")->mutationCost(), 1.0);
}

TEST(MltJob, ReplayMismatchFailsLoudly) {
  const JobPlan plan = planJob(cornell(), settingsFor("pssmlt-bdpt", 9));
  WorkUnit u = plan.units[2];
  u.startContribution *= 1.01;
  try {
    runWorkUnit(cornell(), plan, u);
    FAIL() << "a wrong start contribution was not detected";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("job seed 9"), std::string::npos) << msg;
    EXPECT_NE(msg.find("chain 2"), std::string::npos) << msg;
    EXPECT_NE(msg.find("candidate " + std::to_string(u.startCandidate)), std::string::npos) << msg;
  }
}

// mmlt allocates mutations by allocationWeights (common/mlt/allocation.h): b_k * sqrt(gbar_k), from the bootstrap's
// candidates and the film bins their light lands in.
TEST(MltJob, MmltAllocatesMutationsByAllocationWeights) {
  RenderSettings s = settingsFor("mmlt", 11);
  s.chains = 40;
  const JobPlan plan = planJob(cornell(), s);
  const Normalization& n = plan.norm;
  ASSERT_EQ(n.bk.size(), 5u);
  const MarkovChainBootstrap boot = bootstrapMarkovChainJob(cornell(), plan.settings);
  const std::vector<double> w = allocationWeights(boot.result.lengths);
  ASSERT_EQ(w.size(), 4u);
  double sumW = 0;
  for (double x : w) sumW += x;
  uint64_t total = 0;
  for (int k = 1; k <= 4; ++k) {
    EXPECT_EQ(n.bk[k], boot.result.lengths[k - 1].estimate.b) << k;
    EXPECT_LT(std::fabs(double(n.mutationsPerLength[k]) - double(n.totalMutations) * w[k - 1] / sumW), 1.0) << k;
    total += n.mutationsPerLength[k];
    uint64_t unitsTotal = 0;
    for (const WorkUnit& u : plan.units)
      if (u.pathLength == k) unitsTotal += u.mutations;
    EXPECT_EQ(unitsTotal, n.mutationsPerLength[k]) << k;
  }
  EXPECT_EQ(total, n.totalMutations);
  EXPECT_EQ(n.totalMutations, uint64_t(std::llround(8.0 * 16 * 12)));
  // Length 1 is the light seen directly: its light lands on the brightest pixels, so it gets less than
  // its share of b.
  EXPECT_LT(double(n.mutationsPerLength[1]) / double(n.totalMutations), 0.5 * n.bk[1] / n.b);
}

// The bootstrap's budget prices a mutation as the plan's mix of lengths costs (bootstrap.h, chainMixCost):
// the mean of chainCost over the mutations the plan gives each length. On the Cornell box length 1 (the
// light seen directly, cheap) holds ~40% of b but gets a few % of the mutations; weighted by b_k alone, the
// price is 0.68x the plan's (seed 11).
TEST(MltJob, BootstrapBudgetPricesThePlansMixOfLengths) {
  RenderSettings s = settingsFor("mmlt", 11);
  const JobPlan plan = planJob(cornell(), s);
  const MarkovChainBootstrap boot = bootstrapMarkovChainJob(cornell(), plan.settings);
  double planCost = 0;
  for (const LengthBootstrap& lb : boot.result.lengths)
    planCost += double(plan.norm.mutationsPerLength[size_t(lb.pathLength)]) * chainCost(lb);
  planCost /= double(plan.norm.totalMutations);
  EXPECT_NEAR(chainMixCost(boot.result.lengths), planCost, 1e-3 * planCost);
  double b = 0, bCost = 0;
  for (const LengthBootstrap& lb : boot.result.lengths) {
    b += lb.estimate.b;
    bCost += lb.estimate.b * chainCost(lb);
  }
  EXPECT_GT(std::fabs(bCost / b - planCost), 0.05 * planCost) << "b_k weights alone would price it alike";
}

// allocationWeights on made-up candidates: a uniform image gives b_k (the plain rule); a length whose light
// lands only on a bright bin is weighted by sqrt of the c-weighted mean of 1 / (I^2 + eps) over its bins.
TEST(MltJob, AllocationWeightsFollowWhereTheLightLands) {
  const uint32_t bins = kAllocationBinsPerAxis * kAllocationBinsPerAxis;
  const size_t N = 64 * bins;
  const auto length = [&](int k, const std::function<double(size_t)>& c) {
    LengthBootstrap lb;
    lb.pathLength = k;
    double sum = 0;
    for (size_t i = 0; i < N; ++i) {
      lb.c.push_back(c(i));
      lb.bin.push_back(c(i) > 0 ? uint32_t(i % bins) : kNoBin);
      sum += c(i);
    }
    lb.estimate.b = sum / double(N);
    return lb;
  };
  BootstrapResult uniform;
  uniform.lengths = {length(1, [](size_t) { return 2.0; }), length(2, [](size_t) { return 1.0; })};
  std::vector<double> w = allocationWeights(uniform.lengths);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NEAR(w[0] / w[1], 2.0, 1e-12);

  // Length 1: c = 1 in bin 0 only (b_1 = 1 / bins); length 2: c = 1 / bins everywhere (b_2 = 1 / bins).
  BootstrapResult lit;
  lit.lengths = {length(1, [&](size_t i) { return i % bins == 0 ? 1.0 : 0.0; }),
                 length(2, [&](size_t) { return 1.0 / bins; })};
  w = allocationWeights(lit.lengths);
  ASSERT_EQ(w.size(), 2u);
  const double iBright = 1.0 + 1.0 / bins, iDark = 1.0 / bins;  // bin images (mean luminance)
  const double gBright = 1 / (iBright * iBright + kAllocationEps), gDark = 1 / (iDark * iDark + kAllocationEps);
  const double gbar2 = (gBright + (bins - 1) * gDark) / bins;
  EXPECT_NEAR(w[0] / w[1], std::sqrt(gBright / gbar2), 1e-9);
  EXPECT_LT(w[0] / w[1], 0.2);

  BootstrapResult unbinned = lit;
  unbinned.lengths[0].bin.clear();
  EXPECT_TRUE(allocationWeights(unbinned.lengths).empty());  // the plain rule
}

bool samePlan(const JobPlan& a, const JobPlan& b) {
  if (a.units.size() != b.units.size() || a.settings.chains != b.settings.chains) return false;
  for (size_t i = 0; i < a.units.size(); ++i) {
    const WorkUnit &u = a.units[i], &v = b.units[i];
    if (u.index != v.index || u.startCandidate != v.startCandidate || u.mutations != v.mutations ||
        u.pathLength != v.pathLength || std::memcmp(&u.startContribution, &v.startContribution, sizeof(double)) != 0)
      return false;
  }
  return std::memcmp(&a.norm.b, &b.norm.b, sizeof(double)) == 0 && a.norm.bk == b.norm.bk &&
         a.norm.bkStdErr == b.norm.bkStdErr && a.norm.mutationsPerLength == b.norm.mutationsPerLength &&
         a.norm.totalMutations == b.norm.totalMutations;
}

// A time-budgeted render plans twice from one bootstrap: that must equal planning afresh with the
// chosen mutations per pixel (what `--mutations-per-pixel` does), and a bootstrap computed with other
// settings must be refused.
TEST(MltJob, PlanFromExistingBootstrapEqualsPlanningAfresh) {
  for (std::string m : kMethods) {
    RenderSettings s = settingsFor(m, 13);
    s.chains = 0;
    s.width = 16;
    s.height = 12;
    const MarkovChainBootstrap boot = bootstrapMarkovChainJob(cornell(), s);
    for (double mpp : {3.0, 37.2, 1500.0}) {
      s.mutationsPerPixel = mpp;
      EXPECT_TRUE(samePlan(planMarkovChainJob(cornell(), s, boot), planJob(cornell(), s))) << m.c_str() << " " << mpp;
    }
    RenderSettings other = s;
    other.seed = 14;
    EXPECT_THROW(planMarkovChainJob(cornell(), other, boot), std::invalid_argument);
    other = s;
    other.bootstrapSamples = 4001;
    EXPECT_THROW(planMarkovChainJob(cornell(), other, boot), std::invalid_argument);
    other = s;
    other.integrator.maxDepth = 3;
    EXPECT_THROW(planMarkovChainJob(cornell(), other, boot), std::invalid_argument);
    other = s;  // not read by the bootstrap: allowed
    other.largeStepProb = 0.5f;
    other.chains = 5;
    EXPECT_NO_THROW(planMarkovChainJob(cornell(), other, boot));
  }
}

// The render summary's numbers: acceptance and per-length counts add up to what the chains report, and
// the metadata round trip (used to print the summary of a farm render) loses nothing.
TEST(MltJob, ChainReportMatchesTheChainsAndSurvivesMetadata) {
  const JobPlan plan = planJob(cornell(), settingsFor("mmlt", 15));
  PartialResult merged;
  for (const PartialResult& p : runAll(cornell(), plan)) merged.add(p);
  const ChainReport r = makeChainReport(plan, merged);
  EXPECT_EQ(r.chains, plan.units.size());
  EXPECT_EQ(r.mutations, plan.norm.totalMutations);
  uint64_t chains = 0, mutations = 0;
  double accepted = 0;
  ASSERT_EQ(r.lengths.size(), 4u);  // k = 1..4
  const RefinedB refined = refinedB(plan.norm, merged.stats, &merged.film);
  for (const ChainLengthReport& l : r.lengths) {
    EXPECT_EQ(l.bk, refined.perSlot[size_t(l.k)].b);  // as developed: bootstrap and large steps pooled
    EXPECT_EQ(l.bkStdErr, refined.perSlot[size_t(l.k)].stdErr);
    EXPECT_EQ(l.mutations, plan.norm.mutationsPerLength[size_t(l.k)]) << l.k;
    chains += l.chains;
    mutations += l.mutations;
    accepted += l.acceptance * double(l.mutations);
  }
  EXPECT_EQ(chains, r.chains);
  EXPECT_EQ(mutations, r.mutations);
  EXPECT_NEAR(accepted / double(mutations), r.acceptance, 1e-9);
  EXPECT_GT(r.acceptance, 0.0);
  EXPECT_LT(r.acceptance, 1.0);
  ASSERT_EQ(r.kinds.size(), 2u);  // named by the method
  EXPECT_EQ(r.kinds[0].name, "large");
  EXPECT_EQ(r.kinds[1].name, "small");
  EXPECT_NEAR(double(merged.stats.acceptedPerKind[0] + merged.stats.acceptedPerKind[1]),
              r.acceptanceOf("large") * double(r.steps("large")) + r.acceptanceOf("small") * double(r.steps("small")),
              1e-6);
  EXPECT_EQ(r.steps("large") + r.steps("small"), r.mutations);

  ImageMetadata m;
  m.strings["method"] = "mmlt";
  addChainMetadata(r, m);
  addMoveSecondsMetadata(r, m);  // as the in-process image has them (the summary prints mutations/s per move)
  const ChainReport back = chainReportFromMetadata(m);
  EXPECT_EQ(formatChainSummary(back, 1.5, 2.5), formatChainSummary(r, 1.5, 2.5));
  EXPECT_EQ(back.settings.largeStepProb, plan.settings.largeStepProb);
  EXPECT_EQ(back.settings.kelemenS1, plan.settings.kelemenS1);
  EXPECT_EQ(m.strings.at("kernel"), "kelemen");
  EXPECT_EQ(m.strings.at("splatting"), "kelemen-mis");  // mmlt's default
  EXPECT_EQ(back.settings.splatting, MltSplatting::KelemenMIS);
  const std::string text = formatChainSummary(r, 1.5, 2.5);
  EXPECT_NE(text.find("b = "), std::string::npos) << text;
  EXPECT_NE(text.find("acceptance"), std::string::npos) << text;
  EXPECT_NE(text.find("mutations/s"), std::string::npos) << text;
  EXPECT_EQ(back.b, r.b);
  EXPECT_EQ(back.bStdErr, r.bStdErr);
  EXPECT_EQ(back.bBootstrap, plan.norm.b);
  EXPECT_EQ(back.bSamples, r.bSamples);
  ASSERT_EQ(back.kinds.size(), r.kinds.size());
  for (size_t k = 0; k < r.kinds.size(); ++k) {
    EXPECT_EQ(back.kinds[k].name, r.kinds[k].name);
    EXPECT_EQ(back.kinds[k].proposed, r.kinds[k].proposed);
  }
  EXPECT_EQ(m.strings.at("mutationKinds"), "large,small");
  EXPECT_TRUE(m.numbers.count("acceptanceLarge") && m.numbers.count("smallSteps"));
  // A relative standard error of b above 2% gets a warning.
  ChainReport vague = r;
  vague.bStdErr = 2 * kMaxRelativeStdErrB * r.b;
  EXPECT_NE(chainWarnings(vague).find("relative standard error of b"), std::string::npos);
  ChainReport precise = r;
  precise.bStdErr = 0.5 * kMaxRelativeStdErrB * r.b;
  EXPECT_EQ(chainWarnings(precise), "");
}

TEST(MltJob, CrowdedStartsAreNamedBeforeAnyChainRuns) {
  // chain_report.h, crowdedStart. caustic-mirror at 256x256 (`mltfarm render scenes/caustic-mirror.xml --method
  // mmlt --width 256 --height 256 --mutations-per-pixel 95.1 --bootstrap 17536 --seed 9`, what `--time 16`
  // chose for that seed): the bootstrap met a path of length 6 far above its share and 34 of that length's 57
  // chains start on it (their pixel came out at 658 against the reference's 1.38, relMSE 184; docs/CHAINS.md).
  // The plan alone shows it, the warning names it and the image's metadata carries it; the small Cornell
  // box's plan has no crowd.
  SceneDesc desc = loadScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/caustic-mirror.xml");
  desc.camera.width = desc.camera.height = 256;
  const std::unique_ptr<RenderScene> scene = RenderScene::build(desc);
  RenderSettings s;
  s.method = "mmlt";
  s.seed = 9;
  s.integrator.maxDepth = desc.maxDepth.value_or(5);
  s.mutationsPerPixel = 95.1;
  s.bootstrapSamples = 17536;
  const JobPlan plan = planJob(*scene, s);
  const ChainReport::CrowdedStart c = crowdedStart(plan);
  ASSERT_GE(c.chains, kCrowdedStartChains);
  EXPECT_GE(double(c.chains), kCrowdedStartShare * double(c.of));
  uint64_t onIt = 0, ofLength = 0;  // recounted from the plan's units
  for (const WorkUnit& u : plan.units)
    if (u.pathLength == c.k && u.mutations > 0) {
      ++ofLength;
      onIt += u.startCandidate == c.candidate;
    }
  EXPECT_EQ(onIt, c.chains);
  EXPECT_EQ(ofLength, c.of);
  const ChainReport r = makeChainReport(plan, PartialResult{});
  EXPECT_EQ(r.crowdedStart.chains, c.chains);
  const std::string w = chainWarnings(r);
  EXPECT_NE(w.find(fmt::format("{} of the {} chains of path length {} start from one bootstrap candidate", c.chains,
                               c.of, c.k)),
            std::string::npos)
      << w;
  ImageMetadata m;
  addChainMetadata(r, m);
  const ChainReport back = chainReportFromMetadata(m);
  EXPECT_EQ(back.crowdedStart.k, c.k);
  EXPECT_EQ(back.crowdedStart.chains, c.chains);
  EXPECT_EQ(back.crowdedStart.of, c.of);
  EXPECT_EQ(back.crowdedStart.candidate, c.candidate);
  EXPECT_EQ(chainWarnings(back), w);

  const std::unique_ptr<RenderScene> box = RenderScene::build(test::smallCornellBox(16, 12));
  RenderSettings b;
  b.method = "mmlt";
  b.mutationsPerPixel = 256;
  b.chains = 64;
  const JobPlan calm = planJob(*box, b);
  EXPECT_EQ(crowdedStart(calm).chains, 0u);
  EXPECT_EQ(chainWarnings(makeChainReport(calm, PartialResult{})).find("start from one"), std::string::npos);
}

// Image mean of a render, averaged over `runs` seeds, with its standard error.
struct MeanSe { double mean, se; };
MeanSe imageMean(std::string m, int chains, int runs, uint64_t seed0) {
  std::vector<double> means;
  for (int r = 0; r < runs; ++r) {
    RenderSettings s = settingsFor(m, seed0 + r);
    s.chains = chains;
    s.mutationsPerPixel = 24;
    const JobPlan plan = planJob(cornell(), s);
    PartialResult merged;
    for (const PartialResult& p : runAll(cornell(), plan)) merged.add(p);
    double sum = 0;
    for (const Color& c : developImage(plan, merged)) sum += luminance(c);
    means.push_back(sum / (16 * 12));
  }
  double mean = 0, sq = 0;
  for (double v : means) mean += v;
  mean /= runs;
  for (double v : means) sq += (v - mean) * (v - mean);
  return {mean, std::sqrt(sq / (runs - 1) / runs)};
}

TEST(MltJob, ManyShortChainsAgreeWithOneLongChain) {
  // K = 24 chains of M mutations vs 1 chain of 24 M: same expectation. 12 independent runs each; the
  // difference must be within 4.5 combined standard errors (t with ~22 dof: p ~ 2e-4).
  const MeanSe many = imageMean("pssmlt", 24, 12, 100), one = imageMean("pssmlt", 1, 12, 200);
  EXPECT_NEAR(many.mean, one.mean, 4.5 * std::hypot(many.se, one.se))
      << "24 chains: " << many.mean << " +- " << many.se << ", 1 chain: " << one.mean << " +- " << one.se;
}

}  // namespace
}  // namespace mlt
