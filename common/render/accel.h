// The one class that talks to Embree 3. Everything else sees rays and SurfaceHits.
#pragma once
#include <memory>
#include <optional>
#include <vector>

#include "common/interfaces/interaction.h"
#include "common/scene/scene_desc.h"

namespace mlt {

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
  Bounds3 bounds() const { return bounds_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Bounds3 bounds_;
};

}  // namespace mlt
