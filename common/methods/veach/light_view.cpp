// The light-view pass of veach-mlt (see light_view.h).
#include "common/methods/veach/light_view.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "common/film/sparse_splats.h"
#include "common/methods/veach/path.h"
#include "common/mlt/develop.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"

namespace mlt::veach {

namespace {

constexpr uint64_t kStream = 0x6c69676874766965ULL;  // "lightvie": the pass's generators

// ceil(a b / c) without overflow (a, b up to 2^64; c > 0).
uint64_t mulDivCeil(uint64_t a, uint64_t b, uint64_t c) {
  const unsigned __int128 p = static_cast<unsigned __int128>(a) * b;
  return static_cast<uint64_t>((p + c - 1) / c);
}

// The global mutation offset C_u of every chain unit (by unit index) and M, the plan's mutations in all.
struct ChainOffsets {
  std::vector<uint64_t> offset;  // by unit index; meaningful for chain units
  uint64_t total = 0;
};

ChainOffsets chainOffsets(const JobPlan& plan) {
  ChainOffsets o;
  uint32_t maxIndex = 0;
  for (const WorkUnit& w : plan.units) maxIndex = std::max(maxIndex, w.index);
  o.offset.assign(plan.units.empty() ? 0 : size_t(maxIndex) + 1, 0);
  std::vector<const WorkUnit*> chains;
  for (const WorkUnit& w : plan.units)
    if (w.mutations > 0) chains.push_back(&w);
  std::sort(chains.begin(), chains.end(), [](const WorkUnit* a, const WorkUnit* b) { return a->index < b->index; });
  for (const WorkUnit* w : chains) {
    o.offset[w->index] = o.total;
    o.total += w->mutations;
  }
  return o;
}

std::pair<uint64_t, uint64_t> rangeOf(uint64_t offset, uint64_t mutations, uint64_t total, uint64_t samples) {
  if (total == 0) return {0, 0};
  return {mulDivCeil(offset, samples, total), mulDivCeil(offset + mutations, samples, total)};
}

uint64_t multiplierFor(uint64_t pixels) {
  // About the golden ratio of the film apart, so consecutive samples land far from each other.
  uint64_t a = std::max<uint64_t>(1, uint64_t(0.6180339887498949 * double(pixels))) | 1;
  while (std::gcd(a, pixels) != 1) a += 2;
  return a;
}

// (i a) mod pixels, with a = multiplierFor(pixels).
uint64_t permutedPixel(uint64_t i, uint64_t pixels, uint64_t a) {
  return static_cast<uint64_t>((static_cast<unsigned __int128>(i % pixels) * a) % pixels);
}

}  // namespace

uint32_t lightViewSpp(double ratio, double mutationsPerPixel) {
  if (!(ratio > 0)) return 0;
  return uint32_t(std::max(1.0, std::min(std::round(ratio * mutationsPerPixel), 1e6)));
}

size_t lightViewLayer() { return bStrataLayer(0) + 1; }

uint64_t lightViewPixel(uint64_t i, uint64_t pixels) { return permutedPixel(i, pixels, multiplierFor(pixels)); }

std::pair<uint64_t, uint64_t> lightViewRange(const JobPlan& plan, const WorkUnit& unit, uint32_t sppLV) {
  if (sppLV == 0 || unit.mutations == 0) return {0, 0};
  const ChainOffsets o = chainOffsets(plan);
  if (unit.index >= o.offset.size())
    throw std::invalid_argument("light-view pass: work unit " + std::to_string(unit.index) + " is not in the plan");
  const uint64_t P = uint64_t(plan.settings.width) * uint64_t(plan.settings.height);
  return rangeOf(o.offset[unit.index], unit.mutations, o.total, P * sppLV);
}

Color lightViewRadiance(const PathSpace& space, Vec2 pRaster, Pcg32& rng) {
  const RenderScene& scene = space.scene();
  const Camera& camera = scene.camera();
  const Vec2 uLens = rng.uniform2();
  const CameraRay cr = camera.generateRay(pRaster, uLens);
  float pdfPos = 0, pdfDir = 0;
  camera.pdfWe(cr.ray, &pdfPos, &pdfDir);
  if (!(pdfDir > 0)) return {};
  // The camera's importance over its sampling density is 1 (bdpt.cpp, generateCameraSubpath).
  Ray ray = cr.ray;
  Color beta(1.0f), L;
  for (int edges = 1; edges <= space.maxEdges(); ++edges) {
    const std::optional<SurfaceHit> hit = scene.intersect(ray);
    if (!hit) break;
    if (hit->light >= 0 && edges >= space.minEdges())
      L += beta * scene.light(hit->light).L(hit->p, hit->ng, hit->uv, -ray.d);  // bdpt's s = 0: beta Le
    if (edges == space.maxEdges()) break;
    const Frame frame(hit->ns);
    const float uComponent = rng.uniform();
    const Vec2 uDir = rng.uniform2();
    const std::optional<BsdfSample> bs =
        scene.bsdf(hit->bsdf).sample(frame.toLocal(-ray.d), uComponent, uDir, BsdfQuery{hit->uv, TransportMode::Radiance});
    if (!bs || !bs->delta || bs->f.isBlack() || !(bs->pdfW > 0)) break;  // a diffuse or glossy vertex ends it
    const Vec3 wi = frame.toWorld(bs->wi);
    beta *= bs->f * (std::fabs(bs->wi.z) / bs->pdfW);
    if (beta.isBlack()) break;
    ray.o = offsetRayOrigin(hit->p, hit->ng, wi);
    ray.d = wi;
    ray.tMin = 0;
    ray.tMax = std::numeric_limits<float>::infinity();
  }
  return L;
}

void renderLightViews(const PathSpace& space, const JobPlan& plan, const WorkUnit& unit, uint32_t sppLV,
                      SparseSplatter& splatter) {
  const auto [first, last] = lightViewRange(plan, unit, sppLV);
  const int W = plan.settings.width;
  const uint64_t P = uint64_t(W) * uint64_t(plan.settings.height);
  const uint64_t a = multiplierFor(P);
  for (uint64_t i = first; i < last; ++i) {
    const uint64_t pixel = permutedPixel(i, P, a);
    const float x = float(pixel % uint64_t(W)), y = float(pixel / uint64_t(W));
    Pcg32 rng(hashKeys(plan.settings.seed, i), kStream);
    // Pixel j's samples are k = i / P = 0 .. sppLV - 1: its Sobol points, stratified over the pixel (a light's
    // outline is what this pass renders).
    const Vec2 jitter = sobolPixelPoint(hashKeys(plan.settings.seed, kStream, pixel), uint32_t(i / P));
    const Color L = lightViewRadiance(space, Vec2(x + jitter.x, y + jitter.y), rng);
    // The pixel's centre names the pixel (a jittered point near a large film's edge can round into the
    // next pixel in float); non-finite values are counted and dropped there, as every splat's.
    if (!L.isBlack()) splatter.addSplat(Vec2(x + 0.5f, y + 0.5f), L);
  }
}

double lightViewScale(const JobPlan& plan, const std::vector<uint32_t>& mergedUnits, uint32_t sppLV) {
  if (sppLV == 0) return 0;
  const ChainOffsets o = chainOffsets(plan);
  const uint64_t P = uint64_t(plan.settings.width) * uint64_t(plan.settings.height);
  std::vector<uint64_t> mutations(o.offset.size(), 0);
  for (const WorkUnit& w : plan.units) mutations[w.index] = w.mutations;
  uint64_t samples = 0;
  for (uint32_t u : mergedUnits) {
    if (u >= mutations.size() || mutations[u] == 0) continue;
    const auto [first, last] = rangeOf(o.offset[u], mutations[u], o.total, P * sppLV);
    samples += last - first;
  }
  return samples > 0 ? double(P) / double(samples) : 0.0;
}

}  // namespace mlt::veach
