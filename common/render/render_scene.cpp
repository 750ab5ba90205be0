// RenderScene::build: validate the description, then build the Embree scene, the camera, the BSDFs and
// the lights (point/spot/directional/constant from SceneDesc::lights, then one area light per emitting
// mesh), preprocess the lights with the scene's bounding sphere and choose lights by power.
#include "common/render/render_scene.h"

#include <stdexcept>
#include <string>

#include "common/bsdf/make_bsdf.h"
#include "common/camera/make_camera.h"
#include "common/emitter/make_light.h"

namespace mlt {

namespace {

void validate(const SceneDesc& desc) {
  if (desc.camera.width <= 0 || desc.camera.height <= 0)
    throw std::runtime_error("camera: film width/height must be > 0 (got " + std::to_string(desc.camera.width) + "x" +
                             std::to_string(desc.camera.height) + ")");
  const int nBsdf = static_cast<int>(desc.bsdfs.size());
  bool emits = !desc.lights.empty();
  for (size_t m = 0; m < desc.meshes.size(); ++m) {
    const MeshDesc& mesh = desc.meshes[m];
    const std::string who = "mesh " + std::to_string(m) + " ('" + mesh.name + "')";
    if (mesh.bsdf < 0 || mesh.bsdf >= nBsdf)
      throw std::runtime_error(who + ": bsdf index " + std::to_string(mesh.bsdf) + " out of range [0, " +
                               std::to_string(nBsdf) + ")");
    for (size_t i = 0; i < mesh.positions.size(); ++i)
      if (!isFinite(mesh.positions[i]))
        throw std::runtime_error(who + ": vertex " + std::to_string(i) + " has a non-finite position");
    for (size_t i = 0; i < mesh.normals.size(); ++i)
      if (!isFinite(mesh.normals[i]))
        throw std::runtime_error(who + ": vertex " + std::to_string(i) + " has a non-finite normal");
    if (mesh.emission) emits = true;
  }
  for (size_t b = 0; b < desc.bsdfs.size(); ++b) {
    const BsdfDesc& bd = desc.bsdfs[b];
    if (bd.type == BsdfDesc::Type::TwoSided && (bd.nested < 0 || bd.nested >= nBsdf))
      throw std::runtime_error("bsdf '" + bd.id + "': nested bsdf index " + std::to_string(bd.nested) + " out of range");
  }
  if (!emits) throw std::runtime_error("scene has no emitters");
}

// A convex emitter's own mesh as a ray target (EmitterSurface), traced by the scene's Accel, which the
// scene keeps alive as long as its lights.
class MeshSurface final : public EmitterSurface {
 public:
  MeshSurface(const Accel& accel, uint32_t mesh) : accel_(accel), mesh_(mesh) {}
  std::optional<SurfaceHit> intersect(const Ray& ray) const override { return accel_.intersectMesh(mesh_, ray); }
  std::optional<SurfaceHit> firstInScene(const Ray& ray) const override { return accel_.intersectIfOn(mesh_, ray); }

 private:
  const Accel& accel_;
  uint32_t mesh_;
};

}  // namespace

std::unique_ptr<RenderScene> RenderScene::build(const SceneDesc& desc) {
  validate(desc);
  std::unique_ptr<RenderScene> s(new RenderScene());
  s->desc_ = desc;
  const SceneDesc& d = s->desc_;

  s->accel_ = std::make_unique<Accel>(d.meshes);
  const Bounds3 b = s->accel_->bounds();
  s->center_ = b.empty() ? Vec3(0, 0, 0) : b.center();
  s->radius_ = b.radius();
  if (!(s->radius_ > 0)) s->radius_ = 1;  // no geometry (or a single point): a unit sphere for infinite lights

  s->camera_ = makeCamera(d.camera);

  s->bsdfs_.reserve(d.bsdfs.size());
  for (const BsdfDesc& bd : d.bsdfs) s->bsdfs_.push_back(makeBsdf(d, bd));

  for (size_t i = 0; i < d.lights.size(); ++i) {
    try {
      s->lights_.push_back(makeLight(d.lights[i]));
    } catch (const std::exception& e) {
      throw std::runtime_error("emitter " + std::to_string(i) + ": " + e.what());
    }
  }
  s->meshLight_.assign(d.meshes.size(), -1);
  for (size_t m = 0; m < d.meshes.size(); ++m) {
    if (!d.meshes[m].emission) continue;
    s->meshLight_[m] = static_cast<int>(s->lights_.size());
    std::shared_ptr<const EmitterSurface> surface;
    if (s->accel_->hasMeshScene(uint32_t(m))) surface = std::make_shared<MeshSurface>(*s->accel_, uint32_t(m));
    s->lights_.push_back(makeAreaLight(d.meshes[m], std::move(surface)));
  }

  std::vector<const Light*> ptrs;
  for (size_t i = 0; i < s->lights_.size(); ++i) {
    s->lights_[i]->preprocess(s->center_, s->radius_);
    if (s->lights_[i]->infinite()) s->infiniteLights_.push_back(static_cast<int>(i));
    ptrs.push_back(s->lights_[i].get());
  }
  s->lightSampler_ = std::make_unique<LightSampler>(ptrs);
  return s;
}

std::optional<SurfaceHit> RenderScene::intersect(const Ray& ray) const {
  std::optional<SurfaceHit> h = accel_->intersect(ray);
  if (h) {
    h->bsdf = desc_.meshes[h->meshId].bsdf;
    h->light = meshLight_[h->meshId];
  }
  return h;
}

// Shadow ray between two surface points, each origin pushed off its surface along its own normal toward
// the other point (a zero normal, e.g. a point light, means no offset). The ray's direction is the
// unnormalized difference, so the segment is t in (0, 1); tMax = 1 - eps keeps the far surface out.
bool RenderScene::visible(const Vec3& p0, const Vec3& n0, const Vec3& p1, const Vec3& n1) const {
  const bool zero0 = n0.x == 0 && n0.y == 0 && n0.z == 0;
  const bool zero1 = n1.x == 0 && n1.y == 0 && n1.z == 0;
  const Vec3 o = zero0 ? p0 : offsetRayOrigin(p0, n0, p1 - p0);
  const Vec3 e = zero1 ? p1 : offsetRayOrigin(p1, n1, p0 - p1);
  Ray r;
  r.o = o;
  r.d = e - o;
  r.tMin = 0;
  r.tMax = 1 - 1e-4f;
  return !accel_->occluded(r);
}

}  // namespace mlt
