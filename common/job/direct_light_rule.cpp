#include "common/job/direct_light_rule.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <vector>

#include "common/core/color.h"
#include "common/core/rng.h"
#include "common/integrators/evaluators.h"
#include "common/mlt/develop.h"  // kDirectMaxSegments
#include "common/sampler/sample_source.h"

namespace mlt {

namespace {

constexpr uint64_t kPilotStreamTag = 0xd17ec7;  // the pilot's numbers: hashKeys(seed, tag, pass), sample i

// Luminance of a bdpt sample's paths by length: at most kDirectMaxSegments - 1 segments (emission seen
// directly), exactly kDirectMaxSegments (one bounce), and longer.
struct ByLength {
  double seen = 0, oneBounce = 0, longer = 0;
};

// Samples [first, first + count) of the pilot's stream `tag`, bdpt at max depth `maxDepth`; sample i lies
// in tile g = i mod strata^2 of a strata x strata grid over the film, at a uniform position in it.
std::vector<ByLength> pilotSamples(const RenderScene& scene, const RenderSettings& settings, int maxDepth,
                                   uint64_t first, uint64_t count, int strata, uint64_t tag) {
  IntegratorSettings integrator = settings.integrator;
  integrator.maxDepth = maxDepth;
  const std::unique_ptr<PathEvaluator> bdpt = makeEvaluator(scene, "bdpt", integrator);
  const int W = settings.width, H = settings.height, tiles = strata * strata;
  const uint64_t seed = hashKeys(settings.seed, kPilotStreamTag, tag);
  std::vector<ByLength> out(count);
  const tbb::blocked_range<uint64_t> samples(first, first + count, 64);
  tbb::parallel_for(samples, [&](const tbb::blocked_range<uint64_t>& range) {
    PathContribution path;
    for (uint64_t i = range.begin(); i != range.end(); ++i) {
      const int g = int(i % uint64_t(tiles)), gx = g % strata, gy = g / strata;
      const int x0 = gx * W / strata, x1 = std::max(x0 + 1, (gx + 1) * W / strata);
      const int y0 = gy * H / strata, y1 = std::max(y0 + 1, (gy + 1) * H / strata);
      const float u = hashUniform(seed, i, 0xf1), v = hashUniform(seed, i, 0xf2);
      const Vec2 pixel{float(std::min(x1 - 1, x0 + int(u * float(x1 - x0)))),
                       float(std::min(y1 - 1, y0 + int(v * float(y1 - y0))))};
      IndependentSource source(seed, i);
      path.clear();
      bdpt->evaluate(source, &pixel, path);
      ByLength& o = out[i - first];
      for (const Splat& sp : path.splats) {
        if (!sp.L.isFinite()) continue;
        const int length = sp.s + sp.t - 1;
        (length < kDirectMaxSegments ? o.seen : length == kDirectMaxSegments ? o.oneBounce : o.longer) += luminance(sp.L);
      }
    }
  });
  return out;
}

}  // namespace

DirectLightPilot directLightPilot(const RenderScene& scene, const RenderSettings& settings, PilotUse use) {
  const auto start = std::chrono::steady_clock::now();
  const auto done = [&](DirectLightPilot& out) {
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
  };
  DirectLightPilot out;
  out.decided = use == PilotUse::Decide;

  // The share, from samples of every length: kPilotShareFirst of them, then (unless they already put it
  // far below the threshold) the rest of kPilotShareSamples. Summed in index order, so the share is the
  // same number whether or not the first ones could have stopped it.
  double direct = 0, all = 0;
  const auto addShare = [&](uint64_t first, uint64_t count) {
    for (const ByLength& x : pilotSamples(scene, settings, settings.integrator.maxDepth, first, count, 1, 1)) {
      direct += x.seen + x.oneBounce;
      all += x.seen + x.oneBounce + x.longer;
    }
    out.samples = first + count;
    out.share = all > 0 ? direct / all : 0;
  };
  addShare(0, kPilotShareFirst);
  if (use == PilotUse::Decide && out.share < kPilotShareStop) return done(out);
  addShare(kPilotShareFirst, kPilotShareSamples - kPilotShareFirst);
  // The CV only where it can change the choice.
  if (use == PilotUse::SizePass || out.share < kDirectMinShare) return done(out);

  // The CV of one-bounce light within strata, from samples limited to kDirectMaxSegments segments.
  const std::vector<ByLength> d = pilotSamples(scene, settings, kDirectMaxSegments, 0, kPilotCvSamples, kPilotStrata, 2);
  const int tiles = kPilotStrata * kPilotStrata;
  std::vector<double> sum(tiles, 0.0), sumSq(tiles, 0.0), count(tiles, 0.0);
  double total = 0;
  for (uint64_t i = 0; i < kPilotCvSamples; ++i) {
    const int g = int(i % uint64_t(tiles));
    const double x = d[i].oneBounce;
    sum[g] += x;
    sumSq[g] += x * x;
    count[g] += 1;
    total += x;
  }
  double within = 0;  // sum_g (sumSq_g - sum_g^2 / n_g)
  for (int g = 0; g < tiles; ++g)
    if (count[g] > 0) within += std::max(0.0, sumSq[g] - sum[g] * sum[g] / count[g]);
  const double n = double(kPilotCvSamples), mean = total / n;
  out.samples += kPilotCvSamples;
  out.cv = mean > 0 ? std::sqrt(within / n) / mean : 0;
  out.separate = out.cv <= kDirectMaxCv;  // the share is at least kDirectMinShare here
  return done(out);
}

}  // namespace mlt
