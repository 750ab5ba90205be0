// What b_k's samples could be (issue 9, "brightness exact to 0.1%"): mmlt estimates b_k = integral of c_k over
// primary sample space from its bootstrap candidates and its chains' large steps, each one technique (s, t)
// chosen by a coordinate of u and weighted by the technique count n = k + 1:
//     c_k(u) = n w_{s,t}(x) lum(C_{s,t}(x)),   s = floor(n u_technique),                          (B1)
// whose expectation over that one coordinate, the others held, is the sum over every technique:
//     c^_k(u) = sum_{s + t = k + 1} w_{s,t} lum(C_{s,t}),   E[c^_k] = E[c_k] = b_k.              (B2)
// c^ is c conditioned on the other coordinates (Rao-Blackwell: Var c^ <= Var c), at the cost of evaluating
// every technique. On caustic-mirror the paths only s = 0 samples (the caustic seen in the mirror: the
// camera subpath must hit the small light) are drawn by a sample of c once in n, worth n times as much:
// the heavy tail the results page's brightness shows there (docs/CHAINS.md). This measures, per path length k
// on the bundled scenes at 256x256 and their own depth: the mean of c and of c^ over the same N uniform samples
// (they must agree: a check of (B2)), each one's variance per sample, the share of b in the top 0.1% of the
// samples (the tail), the thread CPU time per sample (c^ by evaluateLength: one camera and one light subpath,
// every connection), and the efficiency ratio (Var c x time c) / (Var c^ x time c^): above 1, a b sample by
// (B2) is worth its cost. Heavy tails make both sample variances unreliable: c's understates its tail where c^
// meets a giant term that c draws once in n (docs/CHAINS.md).
// Run: build/tests/b_estimator_bench [samples per length, default 100000]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "common/integrators/bdpt.h"
#include "common/job/mlt_job.h"
#include "common/methods/mmlt/mmlt_method.h"
#include "common/mlt/target.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"
#include "common/scene/mitsuba_loader.h"

namespace mlt {
namespace {

double threadNs() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e9 + double(ts.tv_nsec);
}

struct Stats {
  std::vector<double> v;
  double ns = 0;
  double mean() const { return std::accumulate(v.begin(), v.end(), 0.0) / double(v.size()); }
  double var() const {
    const double m = mean();
    double q = 0;
    for (double x : v) q += (x - m) * (x - m);
    return q / double(v.size() - 1);
  }
  double topShare() const {  // share of the sum held by the largest 0.1% of the samples
    std::vector<double> s = v;
    const size_t top = std::max<size_t>(1, s.size() / 1000);
    std::nth_element(s.begin(), s.end() - std::ptrdiff_t(top), s.end());
    const double sum = std::accumulate(s.begin(), s.end(), 0.0);
    return sum > 0 ? std::accumulate(s.end() - std::ptrdiff_t(top), s.end(), 0.0) / sum : 0.0;
  }
};

void measure(const std::string& name, uint64_t N) {
  SceneDesc desc = loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + name + ".xml");
  desc.camera.width = desc.camera.height = 256;
  const std::unique_ptr<RenderScene> scene = RenderScene::build(desc);
  IntegratorSettings integrator;
  integrator.maxDepth = desc.maxDepth.value_or(integrator.maxDepth);
  MmltTarget target(*scene, integrator);
  BdptWorkspace ws;
  PathContribution path;
  std::printf("\n%s, mmlt, 256x256, depth %d, %llu uniform samples per length (the same u for c and c^)\n",
              name.c_str(), integrator.maxDepth, static_cast<unsigned long long>(N));
  std::printf("%3s %12s %12s %9s %11s %11s %8s %8s %8s %8s %10s\n", "k", "mean c", "mean c^", "c^/c - 1",
              "var c", "var c^", "top c", "top c^", "ns c", "ns c^", "efficiency");
  for (int k = 2; k <= integrator.maxDepth; ++k) {
    Stats c, ch;
    c.v.resize(N);
    ch.v.resize(N);
    const uint64_t first = uint64_t(k) << kCandidateSlotBits;
    double t0 = threadNs();
    for (uint64_t i = 0; i < N; ++i) {  // (B1), as the bootstrap and the large steps evaluate it
      IndependentSource source = IndependentSource::candidate(7, first + i);
      target.evaluate(source, k, path);
      c.v[i] = targetFunction(path);
    }
    c.ns = (threadNs() - t0) / double(N);
    t0 = threadNs();
    for (uint64_t i = 0; i < N; ++i) {  // (B2): every technique on the same numbers, the subpaths traced once
      IndependentSource source = IndependentSource::candidate(7, first + i);
      ch.v[i] = mmltBSample(*scene, source, k, integrator.heuristic, ws);  // what --b-sample-every draws
    }
    ch.ns = (threadNs() - t0) / double(N);
    const double mc = c.mean(), mh = ch.mean();
    const double eff = ch.var() > 0 ? (c.var() * c.ns) / (ch.var() * ch.ns) : 0.0;
    std::printf("%3d %12.5g %12.5g %+8.2f%% %11.4g %11.4g %7.1f%% %7.1f%% %8.0f %8.0f %10.2f\n", k, mc, mh,
                mc > 0 ? 100 * (mh / mc - 1) : 0.0, c.var(), ch.var(), 100 * c.topShare(), 100 * ch.topShare(),
                c.ns, ch.ns, eff);
  }
}

}  // namespace
}  // namespace mlt

int main(int argc, char** argv) {
  const uint64_t N = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 100000;
  if (N < 2) {
    std::fprintf(stderr, "b_estimator_bench: need at least 2 samples per length, got %s\n", argv[1]);
    return 1;
  }
  for (const char* scene : {"caustic-mirror", "cornell-spheres", "cornell-box"}) mlt::measure(scene, N);
  return 0;
}
