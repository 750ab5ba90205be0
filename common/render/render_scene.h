// The built, render-ready scene: acceleration structure, BSDFs, lights, camera. Immutable after build;
// shared read-only by every thread of a process.
#pragma once
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/emitter/light_sampler.h"
#include "common/interfaces/bsdf.h"
#include "common/interfaces/camera.h"
#include "common/interfaces/light.h"
#include "common/render/accel.h"
#include "common/scene/scene_desc.h"

namespace mlt {

class RenderScene {
 public:
  // Throws std::runtime_error with a message naming the offending element.
  static std::unique_ptr<RenderScene> build(const SceneDesc& desc);

  // Closest hit with bsdf and light indices filled in.
  std::optional<SurfaceHit> intersect(const Ray& ray) const;
  bool occluded(const Ray& ray) const { return accel_->occluded(ray); }
  // True if the segment between two surface points (each offset along its own ng) is unblocked.
  bool visible(const Vec3& p0, const Vec3& n0, const Vec3& p1, const Vec3& n1) const;

  const Camera& camera() const { return *camera_; }
  const Bsdf& bsdf(int index) const { return *bsdfs_[index]; }
  const std::vector<std::unique_ptr<Light>>& lights() const { return lights_; }
  const Light& light(int index) const { return *lights_[index]; }
  const LightSampler& lightSampler() const { return *lightSampler_; }
  // Infinite lights (constant environment), looked up when a ray escapes.
  const std::vector<int>& infiniteLights() const { return infiniteLights_; }
  Vec3 center() const { return center_; }
  float radius() const { return radius_; }
  const SceneDesc& desc() const { return desc_; }

 private:
  RenderScene() = default;
  SceneDesc desc_;
  std::unique_ptr<Accel> accel_;
  std::unique_ptr<Camera> camera_;
  std::vector<std::unique_ptr<Bsdf>> bsdfs_;
  std::vector<std::unique_ptr<Light>> lights_;
  std::vector<int> meshLight_;          // mesh index -> light index or -1
  std::vector<int> infiniteLights_;
  std::unique_ptr<LightSampler> lightSampler_;
  Vec3 center_;
  float radius_ = 0;
};

}  // namespace mlt
