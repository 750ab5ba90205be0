// Where one Markov-chain mutation's time goes (issue 9, item 4: throughput toward the ray floor), for
// pssmlt, pssmlt-bdpt and mmlt on the bundled Cornell box (scenes/cornell-box.xml) at 256x256, depth 5.
//
// Method: record, then time each component in isolation on the recorded inputs. Setup (not timed) plans
// the job exactly like the farm (planJob: bootstrap + chains) and runs kUnits of its chains (spread over
// the plan, so mmlt's path lengths are represented in proportion) for kMutations mutations in all,
// recording per mutation: the mutation type, accept/reject, every primary-sample coordinate read
// (stream, index, value), the path contribution's splats, and every ray traced (Accel's RayObserver).
// Then, each timed alone on the same chains (single thread, best of the benchmark's iterations):
//   total       the chain loop as the job runs it: runChain(PssState(KelemenSource), PssChainTarget,
//               FilmSink) -- what mlt_bench measures per mutation;
//   eval        the method's PssTarget evaluations fed the recorded numbers by a replay source (no mutation
//               arithmetic): rays + BSDF/light evaluation and sampling + integrator bookkeeping;
//   rays        the recorded rays traced alone through RenderScene::intersect / occluded (Embree);
//   mutation    a fresh KelemenSource driven through the recorded protocol: startIteration(), the recorded
//               reads (startStream/seek/next1D, as the evaluators call them), accept()/reject();
//   chain+splat runChain with a replay state and a replay target (recorded types and splats) into a real
//               FilmSink: acceptance, weights, splat bookkeeping and the film writes;
//   chain only  the same with a sink that does nothing (so film writes = chain+splat - chain only).
// Derived: shading = eval - rays (BSDF, lights, camera, MIS, vertex bookkeeping); unattributed = total -
// (eval + mutation + chain+splat) (interaction between the parts: caches, branch predictors, the extra
// virtual hop of the real source).
// Ray floor = rays per mutation x ns per ray, with ns per ray (a) of the recorded chain rays (incoherent)
// and (b) measured like rays_bench (camera rays at 256x256 closest hit, one shadow ray per hit to a point
// sampled on the light; same scene), weighted by the chain's closest/shadow mix.
//
// Times are thread CPU time (the build machine is shared), best over the benchmark's iterations.
// Run: build/tests/mutation_cost_bench --benchmark_min_time=0.5   (the table is printed at the end)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <ctime>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/film/film.h"
#include "common/job/mlt_job.h"
#include "common/methods/registry.h"
#include "common/mlt/chain.h"
#include "common/mlt/kelemen_source.h"
#include "common/methods/pss_method.h"
#include "common/mlt/pss_chain.h"
#include "common/mlt/target.h"
#include "common/render/accel.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"

namespace mlt {
namespace {

constexpr int kRes = 256;
constexpr int kDepth = 5;
constexpr uint64_t kMutations = 1 << 16;  // recorded per method
constexpr size_t kUnits = 8;              // chains they are spread over

// Thread CPU time: the machine is shared, wall time would count other processes' time slices.
struct Clock {
  using time_point = double;
  static double now() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) * 1e9 + double(ts.tv_nsec);
  }
};
double nsSince(double t0) { return Clock::now() - t0; }

struct Bundled {
  std::unique_ptr<RenderScene> scene;
  int rrDepth = 5;
};
const Bundled& bundled() {
  static const Bundled b = [] {
    SceneDesc desc = loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/cornell-box.xml");
    desc.camera.width = desc.camera.height = kRes;
    Bundled r;
    r.rrDepth = desc.rrDepth.value_or(5);
    r.scene = RenderScene::build(desc);
    return r;
  }();
  return b;
}


ChainConfig chainConfig(const JobPlan& plan, int k) {  // as runMarkovChain
  const RenderSettings& s = plan.settings;
  ChainConfig c;
  c.splatting = s.splatting == MltSplatting::ExpectedValue ? ChainSplatting::ExpectedValue : ChainSplatting::KelemenMIS;
  c.largeStepProb = s.largeStepProb;
  c.b = s.method == "mmlt" ? plan.norm.bk[k] : plan.norm.b;
  return c;
}

// ---- recording ---------------------------------------------------------------------------------------

struct Read {
  int16_t stream;
  int32_t index;
  float value;
};
struct RecRay {
  Ray ray;
  bool shadow;
};

struct RecordedChain {
  WorkUnit unit;
  uint64_t mutations = 0;
  std::vector<Read> reads;             // evaluation 0 = the start replay, then one per mutation
  std::vector<size_t> readBegin;       // per evaluation, into reads (+ end sentinel)
  std::vector<Splat> splats;
  std::vector<size_t> splatBegin;      // per evaluation, into splats (+ end sentinel)
  std::vector<Vec2> cameraRaster;      // per evaluation
  std::vector<uint8_t> type, accepted; // per mutation
  std::vector<RecRay> rays;
  uint64_t closest = 0, shadow = 0;
  uint64_t acceptedCount = 0;
};

class RecordingSource final : public SampleSource {
 public:
  RecordingSource(SampleSource& inner, std::vector<Read>& out) : inner_(inner), out_(out) {}
  void startStream(Stream s) override { stream_ = int(s); next_ = 0; inner_.startStream(s); }
  void seek(int index) override { next_ = index; inner_.seek(index); }
  float next1D() override {
    const float v = inner_.next1D();
    out_.push_back({int16_t(stream_), next_++, v});
    return v;
  }

 private:
  SampleSource& inner_;
  std::vector<Read>& out_;
  int stream_ = 0, next_ = 0;
};

class RayRecorder final : public RayObserver {
 public:
  explicit RayRecorder(RecordedChain& rec) : rec_(rec) {}
  void closestHit(const Ray& r) override { rec_.rays.push_back({r, false}); ++rec_.closest; }
  void shadow(const Ray& r) override { rec_.rays.push_back({r, true}); ++rec_.shadow; }

 private:
  RecordedChain& rec_;
};

class RecordingState final : public ChainState {
 public:
  RecordingState(KelemenSource& s, RecordedChain& rec) : inner_(s), rec_(rec) {}
  Proposal propose() override {
    const Proposal p = inner_.propose();
    rec_.type.push_back(uint8_t(p.kind));
    return p;
  }
  void accept() override { rec_.accepted.push_back(1); inner_.accept(); }
  void reject() override { rec_.accepted.push_back(0); inner_.reject(); }

 private:
  PssState inner_;
  RecordedChain& rec_;
};

// After an evaluation: its reads are recorded already; close its ranges (begin vectors start with {0}).
void noteEvaluation(RecordedChain& rec, const PathContribution& out) {
  rec.splats.insert(rec.splats.end(), out.splats.begin(), out.splats.end());
  rec.readBegin.push_back(rec.reads.size());
  rec.splatBegin.push_back(rec.splats.size());
  rec.cameraRaster.push_back(out.cameraRaster);
}

class RecordingTarget final : public ChainTarget {
 public:
  RecordingTarget(PssTarget& t, SampleSource& s, int k, RecordedChain& rec) : t_(t), s_(s), k_(k), rec_(rec) {}
  void evaluate(PathContribution& out) override {
    t_.evaluate(s_, k_, out);
    noteEvaluation(rec_, out);
  }

 private:
  PssTarget& t_;
  SampleSource& s_;
  int k_;
  RecordedChain& rec_;
};

class NullSink final : public ChainSink {
 public:
  void splat(const PathContribution& path, double weight) override { benchmark::DoNotOptimize(weight); }
};

struct MethodData {
  std::string method;
  JobPlan plan;
  std::vector<RecordedChain> chains;
  uint64_t mutations = 0, rays = 0, closest = 0, shadow = 0;
};

RecordedChain record(const JobPlan& plan, const WorkUnit& unit, uint64_t mutations) {
  const RenderScene& scene = *bundled().scene;
  const RenderSettings& s = plan.settings;
  RecordedChain rec;
  rec.unit = unit;
  rec.mutations = mutations;
  rec.readBegin = {0};
  rec.splatBegin = {0};
  KelemenSource source(kelemenParams(s), s.seed, unit.index, unit.startCandidate);
  const std::unique_ptr<PssTarget> targetPtr = findPrimarySampleChainMethod(s.method)->makeTarget(scene, s);
    PssTarget& target = *targetPtr;
  RecordingSource recSource(source, rec.reads);
  RayRecorder rays(rec);
  RayObserver* previous = setThreadRayObserver(&rays);
  PathContribution current, scratch;
  target.evaluate(recSource, unit.pathLength, current);
  noteEvaluation(rec, current);
  const double c0 = targetFunction(current);
  if (!(c0 > 0)) throw std::runtime_error("record: start state has c = 0");
  source.accept();
  RecordingState state(source, rec);
  RecordingTarget chainTarget(target, recSource, unit.pathLength, rec);
  Film film(s.width, s.height);
  FilmSink sink(film, chainLayer(size_t(std::max(unit.pathLength, 0))));  // as the job splats
  Pcg32 acceptRng = chainRng(s.seed, unit.index, 1);
  const ChainCounts counts =
      runChain(state, chainTarget, chainConfig(plan, std::max(unit.pathLength, 0)), sink, acceptRng, mutations,
               current, c0, scratch);
  setThreadRayObserver(previous);
  rec.acceptedCount = counts.accepted[0] + counts.accepted[1];
  return rec;
}

MethodData& methodData(std::string m) {
  static std::map<std::string, std::unique_ptr<MethodData>> cache;
  auto& slot = cache[m];
  if (slot) return *slot;
  slot = std::make_unique<MethodData>();
  MethodData& d = *slot;
  d.method = m;
  RenderSettings s;
  s.method = m;
  s.directLight = DirectLight::Chains;  // every length in the chains, as PERFORMANCE.md's figures were measured
  s.integrator.maxDepth = kDepth;
  s.integrator.rrDepth = bundled().rrDepth;
  s.mutationsPerPixel = 16;
  s.chains = 64;
  s.bootstrapSamples = 20000;
  d.plan = planJob(*bundled().scene, s);
  std::vector<const WorkUnit*> units;
  for (const WorkUnit& u : d.plan.units)
    if (u.mutations > 0) units.push_back(&u);
  const size_t n = std::min(kUnits, units.size());
  for (size_t i = 0; i < n; ++i) {
    const WorkUnit& u = *units[i * units.size() / n];
    d.chains.push_back(record(d.plan, u, kMutations / n));
    const RecordedChain& c = d.chains.back();
    d.mutations += c.mutations;
    d.closest += c.closest;
    d.shadow += c.shadow;
  }
  d.rays = d.closest + d.shadow;
  return d;
}

// ---- the components, each timed alone (ns for every recorded chain) -----------------------------------

double timeTotal(const MethodData& d) {
  const RenderScene& scene = *bundled().scene;
  const RenderSettings& s = d.plan.settings;
  double ns = 0;
  for (const RecordedChain& c : d.chains) {
    KelemenSource source(kelemenParams(s), s.seed, c.unit.index, c.unit.startCandidate);
    const std::unique_ptr<PssTarget> targetPtr = findPrimarySampleChainMethod(s.method)->makeTarget(scene, s);
    PssTarget& target = *targetPtr;
    PathContribution current, scratch;
    target.evaluate(source, c.unit.pathLength, current);
    const double c0 = targetFunction(current);
    source.accept();
    PssState state(source);
    PssChainTarget chainTarget(target, source, c.unit.pathLength);
    Film film(s.width, s.height);
    FilmSink sink(film, chainLayer(size_t(std::max(c.unit.pathLength, 0))));  // as the job splats
    Pcg32 acceptRng = chainRng(s.seed, c.unit.index, 1);
    const ChainConfig config = chainConfig(d.plan, std::max(c.unit.pathLength, 0));
    const auto t0 = Clock::now();
    const ChainCounts counts = runChain(state, chainTarget, config, sink, acceptRng, c.mutations, current, c0, scratch);
    ns += nsSince(t0);
    if (counts.accepted[0] + counts.accepted[1] != c.acceptedCount)
      throw std::logic_error("total: the chain does not reproduce the recording");
  }
  return ns;
}

// Plays back recorded values in order (the evaluation reads the same sequence again).
class PlaybackSource final : public SampleSource {
 public:
  void reset(const Read* r) { r_ = r; }
  void startStream(Stream) override {}
  void seek(int) override {}
  float next1D() override { return (r_++)->value; }
  const Read* position() const { return r_; }

 private:
  const Read* r_ = nullptr;
};

double timeEval(const MethodData& d) {
  const RenderScene& scene = *bundled().scene;
  const RenderSettings& s = d.plan.settings;
  double ns = 0;
  for (const RecordedChain& c : d.chains) {
    const std::unique_ptr<PssTarget> targetPtr = findPrimarySampleChainMethod(s.method)->makeTarget(scene, s);
    PssTarget& target = *targetPtr;
    PlaybackSource source;
    PathContribution out;
    out.splats.reserve(64);
    size_t splats = 0;
    const auto t0 = Clock::now();
    for (size_t e = 1; e + 1 < c.readBegin.size(); ++e) {
      source.reset(c.reads.data() + c.readBegin[e]);
      target.evaluate(source, c.unit.pathLength, out);
      splats += out.splats.size();
    }
    ns += nsSince(t0);
    if (splats != c.splats.size() - c.splatBegin[1]) throw std::logic_error("eval: splats differ from the recording");
  }
  return ns;
}

double timeRays(const MethodData& d) {
  const RenderScene& scene = *bundled().scene;
  double ns = 0;
  for (const RecordedChain& c : d.chains) {
    uint64_t hits = 0;
    const auto t0 = Clock::now();
    for (const RecRay& r : c.rays) {
      if (r.shadow) hits += scene.occluded(r.ray);
      else hits += scene.intersect(r.ray).has_value();
    }
    ns += nsSince(t0);
    benchmark::DoNotOptimize(hits);
  }
  return ns;
}

double timeMutation(const MethodData& d) {
  const RenderSettings& s = d.plan.settings;
  double ns = 0;
  for (const RecordedChain& c : d.chains) {
    KelemenSource kelemen(kelemenParams(s), s.seed, c.unit.index, c.unit.startCandidate);
    SampleSource& source = kelemen;
    uint64_t mismatches = 0;
    // Replays one evaluation's reads through the SampleSource interface, as the evaluators issue them.
    auto replay = [&](size_t e) {
      int stream = -1, next = -1;
      for (size_t i = c.readBegin[e]; i < c.readBegin[e + 1]; ++i) {
        const Read& r = c.reads[i];
        if (r.stream != stream) {
          source.startStream(Stream(r.stream));
          stream = r.stream;
          next = 0;
        }
        if (r.index != next) source.seek(r.index);
        next = r.index + 1;
        mismatches += source.next1D() != r.value;
      }
    };
    replay(0);
    kelemen.accept();
    const auto t0 = Clock::now();
    for (uint64_t m = 0; m < c.mutations; ++m) {
      kelemen.startIteration();
      replay(m + 1);
      if (c.accepted[m]) kelemen.accept();
      else kelemen.reject();
    }
    ns += nsSince(t0);
    if (mismatches) throw std::logic_error("mutation: the source does not reproduce the recording");
  }
  return ns;
}

class PlaybackState final : public ChainState {
 public:
  explicit PlaybackState(const RecordedChain& c) : c_(c) {}
  Proposal propose() override {
    const int kind = c_.type[m_++];
    return {kind, 1.0, kind == int(MutationType::Large)};
  }
  void accept() override {}
  void reject() override {}

 private:
  const RecordedChain& c_;
  size_t m_ = 0;
};

class PlaybackTarget final : public ChainTarget {
 public:
  explicit PlaybackTarget(const RecordedChain& c) : c_(c) {}
  void evaluate(PathContribution& out) override {
    ++e_;
    out.cameraRaster = c_.cameraRaster[e_];
    out.splats.assign(c_.splats.begin() + c_.splatBegin[e_], c_.splats.begin() + c_.splatBegin[e_ + 1]);
  }

 private:
  const RecordedChain& c_;
  size_t e_ = 0;
};

double timeChain(const MethodData& d, bool filmSink) {
  const RenderSettings& s = d.plan.settings;
  double ns = 0;
  for (const RecordedChain& c : d.chains) {
    PathContribution current, scratch;
    current.splats.assign(c.splats.begin() + c.splatBegin[0], c.splats.begin() + c.splatBegin[1]);
    current.splats.reserve(64);
    scratch.splats.reserve(64);
    const double c0 = targetFunction(current);
    PlaybackState state(c);
    PlaybackTarget target(c);
    Film film(s.width, s.height);
    FilmSink fsink(film, chainLayer(size_t(std::max(c.unit.pathLength, 0))));  // as the job splats
    NullSink nsink;
    ChainSink& sink = filmSink ? static_cast<ChainSink&>(fsink) : nsink;
    Pcg32 acceptRng = chainRng(s.seed, c.unit.index, 1);
    const ChainConfig config = chainConfig(d.plan, std::max(c.unit.pathLength, 0));
    const auto t0 = Clock::now();
    const ChainCounts counts = runChain(state, target, config, sink, acceptRng, c.mutations, current, c0, scratch);
    ns += nsSince(t0);
    if (counts.accepted[0] + counts.accepted[1] != c.acceptedCount)
      throw std::logic_error("chain: the playback does not reproduce the recording");
  }
  return ns;
}

// ---- ns per ray like rays_bench, on the bundled scene ---------------------------------------------------

struct CoherentRays {
  std::vector<Ray> camera, shadow;
};
const CoherentRays& coherentRays() {
  static const CoherentRays r = [] {
    const RenderScene& scene = *bundled().scene;
    CoherentRays out;
    Pcg32 rng(1, 2);
    for (int y = 0; y < kRes; ++y)
      for (int x = 0; x < kRes; ++x) {
        const Ray ray = scene.camera().generateRay({x + 0.5f, y + 0.5f}, {0.5f, 0.5f}).ray;
        out.camera.push_back(ray);
        const auto h = scene.intersect(ray);
        if (!h) continue;
        float pmf = 0;
        const int li = scene.lightSampler().sample(rng.uniform(), &pmf);
        if (li < 0) continue;
        const auto ls = scene.light(li).sampleLi(h->p, rng.uniform2());
        if (!ls) continue;
        // The shadow ray RenderScene::visible traces.
        const Vec3 o = offsetRayOrigin(h->p, h->ng, ls->pLight - h->p);
        const bool zero = ls->nLight.x == 0 && ls->nLight.y == 0 && ls->nLight.z == 0;
        const Vec3 e = zero ? ls->pLight : offsetRayOrigin(ls->pLight, ls->nLight, h->p - ls->pLight);
        Ray s;
        s.o = o;
        s.d = e - o;
        s.tMax = 1 - 1e-4f;
        out.shadow.push_back(s);
      }
    return out;
  }();
  return r;
}

// ---- benchmarks and the table -------------------------------------------------------------------------

enum Component { kTotal, kEval, kRays, kMutation, kChainSplat, kChainOnly, kNumComponents };
const char* kComponentNames[] = {"total", "eval", "rays", "mutation", "chain+splat", "chain only"};
std::map<std::string, double> gBest[kNumComponents];  // best ns per mutation
double gCoherentNs[2] = {0, 0};                  // best ns per ray: camera (closest), shadow

void runComponent(benchmark::State& state, std::string m, Component comp) {
  const MethodData& d = methodData(m);
  double best = 1e300;
  for (auto _ : state) {
    double ns = 0;
    switch (comp) {
      case kTotal: ns = timeTotal(d); break;
      case kEval: ns = timeEval(d); break;
      case kRays: ns = timeRays(d); break;
      case kMutation: ns = timeMutation(d); break;
      case kChainSplat: ns = timeChain(d, true); break;
      case kChainOnly: ns = timeChain(d, false); break;
      default: break;
    }
    state.SetIterationTime(ns * 1e-9);
    best = std::min(best, ns / double(d.mutations));
  }
  auto& slot = gBest[comp][m];
  slot = slot > 0 ? std::min(slot, best) : best;
  state.counters["ns/mutation(best)"] = best;
  state.counters["rays/mutation"] = double(d.rays) / double(d.mutations);
  state.counters["mutations/s(best)"] = 1e9 / best;
}

void BM_CoherentRays(benchmark::State& state) {
  const RenderScene& scene = *bundled().scene;
  const CoherentRays& r = coherentRays();
  const bool shadow = state.range(0) == 1;
  double best = 1e300;
  for (auto _ : state) {
    uint64_t hits = 0;
    const auto t0 = Clock::now();
    if (shadow) for (const Ray& ray : r.shadow) hits += scene.occluded(ray);
    else for (const Ray& ray : r.camera) hits += scene.intersect(ray).has_value();
    const double ns = nsSince(t0);
    benchmark::DoNotOptimize(hits);
    state.SetIterationTime(ns * 1e-9);
    best = std::min(best, ns / double(shadow ? r.shadow.size() : r.camera.size()));
  }
  double& slot = gCoherentNs[shadow ? 1 : 0];
  slot = slot > 0 ? std::min(slot, best) : best;
  state.counters["ns/ray(best)"] = best;
}
BENCHMARK(BM_CoherentRays)->Arg(0)->Arg(1)->ArgName("shadow")->UseManualTime()->Unit(benchmark::kMillisecond);

void registerAll() {
  for (std::string m : {"pssmlt", "pssmlt-bdpt", "mmlt"})
    for (int c = 0; c < kNumComponents; ++c)
      benchmark::RegisterBenchmark((std::string("BM_") + m.c_str() + "/" + kComponentNames[c]).c_str(),
                                   [m, c](benchmark::State& s) { runComponent(s, m, Component(c)); })
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond);
}

void printTable() {
  std::printf("\nMutation cost breakdown: scenes/cornell-box.xml, %dx%d, max depth %d, 1 thread, best of N "
              "(ns per mutation; %% of total)\n\n",
              kRes, kRes, kDepth);
  std::printf("| method | total ns | rays | shading (BSDF, light, integrator) | mutation (Kelemen) | "
              "chain loop | film splats | unattributed | rays/mut (closest+shadow) | ns/ray chain / rays_bench-style | "
              "ray floor ns (chain / rays_bench-style) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (std::string m : {"pssmlt", "pssmlt-bdpt", "mmlt"}) {
    bool have = true;
    for (int c = 0; c < kNumComponents; ++c) have = have && gBest[c].count(m);
    if (!have) continue;
    const MethodData& d = methodData(m);
    const double total = gBest[kTotal][m], eval = gBest[kEval][m], rays = gBest[kRays][m];
    const double mut = gBest[kMutation][m], chainSplat = gBest[kChainSplat][m], chain = gBest[kChainOnly][m];
    const double shading = eval - rays, splat = chainSplat - chain, rest = total - eval - mut - chainSplat;
    auto cell = [&](double ns) { return std::to_string(int(ns + 0.5)) + " (" + std::to_string(int(100 * ns / total + 0.5)) + "%)"; };
    const double perMut = double(d.rays) / double(d.mutations);
    const double nsPerRayChain = rays / perMut;
    char buf[512];
    std::string coherent = "-", floorCoherent = "-";
    if (gCoherentNs[0] > 0 && gCoherentNs[1] > 0) {
      const double nsc = (double(d.closest) * gCoherentNs[0] + double(d.shadow) * gCoherentNs[1]) / double(d.rays);
      std::snprintf(buf, sizeof buf, "%.0f", nsc);
      coherent = buf;
      std::snprintf(buf, sizeof buf, "%.0f (%.0f%%)", perMut * nsc, 100 * perMut * nsc / total);
      floorCoherent = buf;
    }
    std::printf("| %s | %.0f | %s | %s | %s | %s | %s | %s | %.2f (%.2f+%.2f) | %.0f / %s | %.0f / %s |\n",
                m.c_str(), total, cell(rays).c_str(), cell(shading).c_str(), cell(mut).c_str(),
                cell(chain).c_str(), cell(splat).c_str(), cell(rest).c_str(), perMut,
                double(d.closest) / double(d.mutations), double(d.shadow) / double(d.mutations), nsPerRayChain,
                coherent.c_str(), rays, floorCoherent.c_str());
  }
  if (gCoherentNs[0] > 0)
    std::printf("\nrays_bench-style ns per ray on this scene: closest hit (camera rays) %.1f, shadow %.1f\n",
                gCoherentNs[0], gCoherentNs[1]);
}

}  // namespace
}  // namespace mlt

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  mlt::registerAll();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  mlt::printTable();
  return 0;
}
