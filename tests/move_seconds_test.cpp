// Mutations per second per move (issue 12): the chain loop (common/mlt/chain.cpp) times its steps per
// move kind, for every chain method (pssmlt and pssmlt-bdpt: large/small; mmlt; rjmlt: large/small/
// technique; veach-mlt: its five moves). Checked here: every kind that was proposed has seconds > 0 and the
// others none; the seconds merge by addition (two partial results give the sum) and reach the
// in-process metadata (NAMESeconds) and the printed summary, but never the deterministic image keys; the
// films do not depend on the timing (same unit twice: the same bits).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "common/job/mlt_job.h"
#include "common/methods/chain_report.h"
#include "common/methods/image_metadata.h"
#include "common/methods/registry.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

const RenderScene& cornell() {
  static const std::unique_ptr<RenderScene> scene = RenderScene::build(test::smallCornellBox(16, 12));
  return *scene;
}

RenderSettings settingsFor(const std::string& method) {
  RenderSettings s;
  s.method = method;
  s.seed = 11;
  s.integrator.maxDepth = 4;
  s.mutationsPerPixel = 16;
  s.bootstrapSamples = 4000;
  s.chains = 8;
  if (method == "rjmlt") s.params["technique-step"] = "0.2";
  return s;
}

struct Job {
  JobPlan plan;
  std::vector<PartialResult> units;
};

Job runJob(const std::string& method) {
  Job j{planJob(cornell(), settingsFor(method)), {}};
  for (const WorkUnit& u : j.plan.units) j.units.push_back(runWorkUnit(cornell(), j.plan, u));
  return j;
}

// Units [begin, end) merged in index order.
PartialResult merged(const Job& j, size_t begin, size_t end) {
  PartialResult r;
  for (size_t i = begin; i < end; ++i) r.add(j.units[i]);
  return r;
}

bool sameSums(const Film& a, const Film& b) {
  if (a.splatLayerCount() != b.splatLayerCount() || a.pixelSums().size() != b.pixelSums().size()) return false;
  for (size_t l = 0; l < a.splatLayerCount(); ++l)
    if (a.hasSplatLayer(l) != b.hasSplatLayer(l) ||
        (a.hasSplatLayer(l) &&
         std::memcmp(a.splatLayer(l).data(), b.splatLayer(l).data(), a.splatLayer(l).size() * sizeof(RGBd)) != 0))
      return false;
  return std::memcmp(a.pixelSums().data(), b.pixelSums().data(), a.pixelSums().size() * sizeof(RGBd)) == 0;
}

const char* const kChainMethods[] = {"pssmlt", "pssmlt-bdpt", "mmlt", "rjmlt", "veach-mlt"};

TEST(MoveSeconds, EveryChainMethodTimesEveryKindItProposed) {
  for (const std::string method : kChainMethods) {
    SCOPED_TRACE(method);
    const Job j = runJob(method);
    const std::vector<std::string>& names = mutationKindNames(method);
    const PartialResult all = merged(j, 0, j.units.size());
    const ChainStats& st = all.stats;
    ASSERT_EQ(st.secondsPerKind.size(), names.size());
    int proposedKinds = 0;
    for (size_t k = 0; k < names.size(); ++k) {
      if (st.proposedPerKind[k] > 0) {
        ++proposedKinds;
        EXPECT_GT(st.secondsPerKind[k], 0.0) << names[k] << ": " << st.proposedPerKind[k] << " proposals";
      } else {
        EXPECT_EQ(st.secondsPerKind[k], 0.0) << names[k] << " was never proposed";
      }
    }
    EXPECT_GE(proposedKinds, 2);
    // Every chain on its own, too (a chain's rarely proposed kind still gets seconds). The direct pass's
    // units (the automatic choice takes it on this box) propose no moves and carry no move statistics.
    for (const PartialResult& u : j.units) {
      if (isDirectUnit(j.plan.units[u.units[0]])) {
        EXPECT_TRUE(u.stats.secondsPerKind.empty());
        continue;
      }
      for (size_t k = 0; k < names.size(); ++k)
        EXPECT_EQ(u.stats.secondsPerKind[k] > 0, u.stats.proposedPerKind[k] > 0) << names[k] << ", unit " << u.units[0];
    }

    // The in-process metadata: NAMESeconds exactly for the kinds proposed; the deterministic keys (the farm's
    // image) have none of them.
    const ChainReport report = makeChainReport(j.plan, all);
    ImageMetadata m;
    addMoveSecondsMetadata(report, m);
    const ImageMetadata deterministic = imageMetadata(j.plan, all, "cornell", "hash");
    for (size_t k = 0; k < names.size(); ++k) {
      const std::string key = names[k] + "Seconds";
      EXPECT_EQ(m.numbers.count(key), st.proposedPerKind[k] > 0 ? 1u : 0u) << key;
      if (m.numbers.count(key)) EXPECT_EQ(m.numbers.at(key), st.secondsPerKind[k]) << key;
      EXPECT_EQ(deterministic.numbers.count(key), 0u) << key << " in the deterministic metadata";
    }
  }
}

TEST(MoveSeconds, PartialResultsMergeBySummingTheSeconds) {
  for (const std::string method : {"rjmlt", "veach-mlt"}) {
    SCOPED_TRACE(method);
    const Job j = runJob(method);
    // Split within the chains (they come first; the direct pass's units, with no moves, after them), so
    // that both halves hold chains whatever the size of the pass.
    const size_t chains = size_t(std::count_if(j.plan.units.begin(), j.plan.units.end(),
                                               [](const WorkUnit& u) { return u.mutations > 0; }));
    const size_t half = chains / 2;
    ASSERT_GT(half, 0u);
    const PartialResult a = merged(j, 0, half), b = merged(j, half, j.units.size());
    PartialResult both = a;
    both.add(b);
    const size_t kinds = mutationKindNames(method).size();
    ASSERT_EQ(a.stats.secondsPerKind.size(), kinds);
    ASSERT_EQ(b.stats.secondsPerKind.size(), kinds);
    ASSERT_EQ(both.stats.secondsPerKind.size(), kinds);
    const ChainReport report = makeChainReport(j.plan, both);
    for (size_t k = 0; k < kinds; ++k) {
      if (a.stats.proposedPerKind[k] > 0) EXPECT_GT(a.stats.secondsPerKind[k], 0.0) << k;
      EXPECT_EQ(both.stats.secondsPerKind[k], a.stats.secondsPerKind[k] + b.stats.secondsPerKind[k]) << k;
      EXPECT_EQ(report.kinds[k].seconds, both.stats.secondsPerKind[k]) << k;
    }
    // A result without the seconds (a partial of an older worker) merges as zero.
    PartialResult old = b;
    old.stats.secondsPerKind.clear();
    PartialResult withOld = a;
    withOld.add(old);
    EXPECT_EQ(withOld.stats.secondsPerKind, a.stats.secondsPerKind);
  }
}

TEST(MoveSeconds, TheTimingLeavesTheFilmsBitIdentical) {
  for (const std::string method : kChainMethods) {
    SCOPED_TRACE(method);
    const JobPlan plan = planJob(cornell(), settingsFor(method));
    PartialResult x = runWorkUnit(cornell(), plan, plan.units[1]);
    PartialResult y = runWorkUnit(cornell(), plan, plan.units[1]);
    x.foldSplats();  // a chain unit's splats travel sparse (common/film/sparse_splats.h)
    y.foldSplats();
    ASSERT_GT(x.film.pixelCount(), 0u);
    EXPECT_TRUE(sameSums(x.film, y.film));
    EXPECT_EQ(x.stats.proposedPerKind, y.stats.proposedPerKind);
    EXPECT_EQ(x.stats.acceptedPerKind, y.stats.acceptedPerKind);
  }
}

TEST(MoveSeconds, TheSummaryPrintsMutationsPerSecondPerMoveAndReadsThemBack) {
  ChainReport r;
  r.method = "rjmlt";
  r.hasAcceptance = true;
  r.mutations = 3000;
  r.kinds = {{"large", 1000, 0.25, 0.5}, {"small", 2000, 0.75, 0.25}, {"technique", 0, 0, 0}};
  const std::string summary = formatChainSummary(r, -1, 1.0);
  EXPECT_NE(summary.find("mutations/s per move, one thread: large 2000 (1000 in 0.5 s), small 8000 (2000 in 0.25 s)\n"),
            std::string::npos)
      << summary;
  EXPECT_EQ(summary.find("technique 0"), std::string::npos) << summary;  // never proposed: no rate

  ImageMetadata m;
  addChainMetadata(r, m);
  addMoveSecondsMetadata(r, m);
  EXPECT_EQ(m.numbers.at("largeSeconds"), 0.5);
  EXPECT_EQ(m.numbers.at("smallSeconds"), 0.25);
  EXPECT_EQ(m.numbers.count("techniqueSeconds"), 0u);
  const ChainReport back = chainReportFromMetadata(m);
  ASSERT_EQ(back.kinds.size(), 3u);
  EXPECT_EQ(back.kinds[0].seconds, 0.5);
  EXPECT_EQ(back.kinds[1].seconds, 0.25);
  EXPECT_EQ(back.kinds[1].mutationsPerSecond(), 8000.0);
  EXPECT_EQ(formatChainSummary(back, -1, 1.0), summary);

  // An image without the seconds (the farm's): no such line.
  ImageMetadata farm;
  addChainMetadata(r, farm);
  EXPECT_EQ(formatChainSummary(chainReportFromMetadata(farm), -1, 1.0).find("per move"), std::string::npos);
}

}  // namespace
}  // namespace mlt
