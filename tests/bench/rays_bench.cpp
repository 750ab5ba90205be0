// Ray throughput of the Embree wrapper on a Cornell-box-like scene built in code (walls, two blocks, a
// ceiling light): closest-hit camera rays at 256x256 and shadow rays from the hit points to points on
// the light. Single thread; the figure printed is rays per second (counter "rays/s").
#include <benchmark/benchmark.h>

#include <vector>

#include "common/core/rng.h"
#include "common/core/sampling.h"
#include "common/camera/make_camera.h"
#include "common/render/accel.h"
#include "common/scene/scene_desc.h"

namespace mlt {
namespace {

constexpr int kRes = 256;

void addQuad(MeshDesc& m, Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  const uint32_t base = static_cast<uint32_t>(m.positions.size());
  m.positions.insert(m.positions.end(), {a, b, c, d});
  m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

// An axis-aligned block [lo, hi] rotated about the vertical axis through its center.
void addBlock(MeshDesc& m, Vec3 lo, Vec3 hi, float angleDeg) {
  const Vec3 c = (lo + hi) * 0.5f;
  const float a = angleDeg * kPi / 180, ca = std::cos(a), sa = std::sin(a);
  auto P = [&](int x, int y, int z) {
    const Vec3 p(x ? hi.x : lo.x, y ? hi.y : lo.y, z ? hi.z : lo.z);
    const Vec3 q = p - c;
    return c + Vec3(ca * q.x + sa * q.z, q.y, -sa * q.x + ca * q.z);
  };
  addQuad(m, P(0, 1, 0), P(0, 1, 1), P(1, 1, 1), P(1, 1, 0));  // top (+y)
  addQuad(m, P(0, 0, 1), P(1, 0, 1), P(1, 1, 1), P(0, 1, 1));  // +z
  addQuad(m, P(1, 0, 0), P(0, 0, 0), P(0, 1, 0), P(1, 1, 0));  // -z
  addQuad(m, P(1, 0, 1), P(1, 0, 0), P(1, 1, 0), P(1, 1, 1));  // +x
  addQuad(m, P(0, 0, 0), P(0, 0, 1), P(0, 1, 1), P(0, 1, 0));  // -x
}

struct CornellBox {
  std::vector<MeshDesc> meshes;
  std::unique_ptr<Camera> camera;
  Vec3 lightLo, lightHi;  // the light quad spans x, z at height lightLo.y
  CornellBox() {
    MeshDesc walls;
    walls.name = "walls";
    addQuad(walls, {-1, -1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, -1, -1});  // floor
    addQuad(walls, {-1, 1, -1}, {1, 1, -1}, {1, 1, 1}, {-1, 1, 1});      // ceiling
    addQuad(walls, {-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1});  // back
    addQuad(walls, {-1, -1, -1}, {-1, 1, -1}, {-1, 1, 1}, {-1, -1, 1});  // left
    addQuad(walls, {1, -1, -1}, {1, -1, 1}, {1, 1, 1}, {1, 1, -1});      // right
    MeshDesc blocks;
    blocks.name = "blocks";
    addBlock(blocks, {-0.7f, -1, -0.6f}, {-0.1f, 0.2f, 0.0f}, 20);
    addBlock(blocks, {0.1f, -1, 0.0f}, {0.7f, -0.4f, 0.6f}, -17);
    MeshDesc light;
    light.name = "light";
    lightLo = {-0.25f, 0.99f, -0.25f};
    lightHi = {0.25f, 0.99f, 0.25f};
    addQuad(light, {-0.25f, 0.99f, -0.25f}, {-0.25f, 0.99f, 0.25f}, {0.25f, 0.99f, 0.25f}, {0.25f, 0.99f, -0.25f});
    light.emission = Color(10);
    meshes = {walls, blocks, light};
    CameraDesc cd;
    cd.toWorld = Transform::lookAt({0, 0, 3.9f}, {0, 0, 0}, {0, 1, 0});
    cd.fovDeg = 39.3f;
    cd.width = cd.height = kRes;
    camera = makeCamera(cd);
  }
};

void BM_ClosestHitCameraRays(benchmark::State& state) {
  const CornellBox box;
  const Accel accel(box.meshes);
  int64_t rays = 0, hits = 0;
  for (auto _ : state) {
    for (int y = 0; y < kRes; ++y)
      for (int x = 0; x < kRes; ++x) {
        const CameraRay c = box.camera->generateRay({x + 0.5f, y + 0.5f}, {0.5f, 0.5f});
        const auto h = accel.intersect(c.ray);
        hits += h.has_value();
        benchmark::DoNotOptimize(h);
      }
    rays += kRes * kRes;
  }
  state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
  state.counters["hit fraction"] = double(hits) / double(std::max<int64_t>(rays, 1));
}
BENCHMARK(BM_ClosestHitCameraRays)->Unit(benchmark::kMillisecond);

void BM_ShadowRaysToLight(benchmark::State& state) {
  const CornellBox box;
  const Accel accel(box.meshes);
  // Primary hits first (not timed), then one shadow ray per hit to a random point on the light.
  std::vector<SurfaceHit> hits;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x)
      if (auto h = accel.intersect(box.camera->generateRay({x + 0.5f, y + 0.5f}, {0.5f, 0.5f}).ray))
        hits.push_back(*h);
  Pcg32 rng(1, 2);
  std::vector<Ray> shadow;
  for (const SurfaceHit& h : hits) {
    const Vec2 u = rng.uniform2();
    const Vec3 pl(box.lightLo.x + u.x * (box.lightHi.x - box.lightLo.x), box.lightLo.y,
                  box.lightLo.z + u.y * (box.lightHi.z - box.lightLo.z));
    Ray r;
    r.o = offsetRayOrigin(h.p, h.ng, pl - h.p);
    r.d = pl - r.o;
    r.tMax = 1 - 1e-4f;
    shadow.push_back(r);
  }
  int64_t rays = 0, blocked = 0;
  for (auto _ : state) {
    for (const Ray& r : shadow) blocked += accel.occluded(r);
    rays += int64_t(shadow.size());
  }
  state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
  state.counters["blocked fraction"] = double(blocked) / double(std::max<int64_t>(rays, 1));
}
BENCHMARK(BM_ShadowRaysToLight)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace mlt

BENCHMARK_MAIN();
