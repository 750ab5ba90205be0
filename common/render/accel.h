// The one class that talks to Embree 3. Everything else sees rays and SurfaceHits.
#pragma once
#include <memory>
#include <optional>
#include <vector>

#include "common/interfaces/interaction.h"
#include "common/scene/scene_desc.h"

namespace mlt {

// Sees every ray an Accel traces on the calling thread, before it is traced (benchmarks record the rays
// of a Markov chain to time them in isolation: tests/bench/mutation_cost_bench.cpp). Off by default; the
// cost when off is one thread-local load per ray.
class RayObserver {
 public:
  virtual ~RayObserver() = default;
  virtual void closestHit(const Ray& ray) = 0;
  virtual void shadow(const Ray& ray) = 0;
};
// Installs `observer` for the calling thread (nullptr = none); returns the previous one.
RayObserver* setThreadRayObserver(RayObserver* observer);

class Accel {
 public:
  // Builds one Embree scene with a triangle geometry per mesh (geometry id = mesh index).
  explicit Accel(const std::vector<MeshDesc>& meshes);
  ~Accel();
  Accel(const Accel&) = delete;
  Accel& operator=(const Accel&) = delete;

  // Closest hit in (ray.tMin, ray.tMax). Fills p, ng, ns, uv, t, meshId, primId (not bsdf/light).
  std::optional<SurfaceHit> intersect(const Ray& ray) const;
  // True if anything blocks the open segment (ray.tMin, ray.tMax).
  bool occluded(const Ray& ray) const;
  // Closest hit against mesh `meshId` alone (an Embree scene of its own, built for every emitting convex
  // mesh: MeshDesc::convex): what a convex area light's cone sampling traces. nullopt on a miss; throws
  // std::logic_error for a mesh that has no scene of its own.
  std::optional<SurfaceHit> intersectMesh(uint32_t meshId, const Ray& ray) const;
  bool hasMeshScene(uint32_t meshId) const;
  // The closest hit of the whole scene in (ray.tMin, ray.tMax) if it lies on mesh `meshId`, else nullopt
  // (completed only then): what a convex area light's next-event estimate traces to find its point and
  // whether anything comes before it in one ray.
  std::optional<SurfaceHit> intersectIfOn(uint32_t meshId, const Ray& ray) const;
  Bounds3 bounds() const { return bounds_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Bounds3 bounds_;
};

}  // namespace mlt
