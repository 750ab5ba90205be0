// The one file that talks to Embree 3: one device, one scene, one triangle geometry per mesh
// (geomID = mesh index), robust traversal, high build quality; an emitting convex mesh's geometry is also
// attached to a scene of its own (intersectMesh: a sphere light's cone sampling). Hits are completed from our own copy of
// the mesh data: ng from the triangle's positions (counter-clockwise = front; computed once per triangle
// at build), ns and uv interpolated with Embree's barycentrics (p = (1-u-v) p0 + u p1 + v p2).
#include "common/render/accel.h"

#include <embree3/rtcore.h>

#include <mutex>
#include <stdexcept>
#include <string>

namespace mlt {

struct Accel::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  // Per mesh: a scene holding that mesh alone (geomID 0), for emitting convex meshes; else null.
  std::vector<RTCScene> meshScenes;
  std::vector<MeshDesc> meshes;  // positions, normals, uvs, indices (names kept for messages)
  // Per mesh and triangle: the unit geometric normal cross(p1 - p0, p2 - p0) / length, computed once with
  // the same float operations a hit used to repeat (the same bits), or ok = false for a degenerate
  // triangle (length 0), whose hit faces the ray instead.
  struct FaceNormal {
    Vec3 ng;
    bool ok;
  };
  std::vector<std::vector<FaceNormal>> faceNormals;
  std::mutex errorMutex;
  std::string error;             // first device error reported by Embree's callback

  ~Impl() {
    for (RTCScene m : meshScenes)
      if (m) rtcReleaseScene(m);
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  static void errorCallback(void* userPtr, RTCError code, const char* str) {
    auto* impl = static_cast<Impl*>(userPtr);
    std::lock_guard<std::mutex> lock(impl->errorMutex);
    if (impl->error.empty()) impl->error = "code " + std::to_string(int(code)) + ": " + (str ? str : "(no message)");
  }
  [[gnu::always_inline]] inline SurfaceHit completeHit(const Ray& ray, const RTCRayHit& rh, uint32_t meshId) const;
  // Throws if Embree reported an error since the last check (the callback must not throw itself).
  void check(const char* what) {
    std::lock_guard<std::mutex> lock(errorMutex);
    if (!error.empty()) throw std::runtime_error(std::string("Embree error during ") + what + ": " + error);
  }
};

namespace {

thread_local RayObserver* tlRayObserver = nullptr;

RTCRayHit toRtc(const Ray& ray) {
  RTCRayHit rh{};
  rh.ray.org_x = ray.o.x;
  rh.ray.org_y = ray.o.y;
  rh.ray.org_z = ray.o.z;
  rh.ray.dir_x = ray.d.x;
  rh.ray.dir_y = ray.d.y;
  rh.ray.dir_z = ray.d.z;
  rh.ray.tnear = ray.tMin;
  rh.ray.tfar = ray.tMax;
  rh.ray.mask = 0xffffffffu;
  rh.ray.flags = 0;
  rh.ray.time = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

constexpr const char* kDeviceConfig = "max_isa=avx2";

}  // namespace

Accel::Accel(const std::vector<MeshDesc>& meshes) : impl_(std::make_unique<Impl>()) {
  Impl& I = *impl_;
  I.meshes = meshes;
  // Embree picks its kernels by the CPU's instruction set at run time, and its AVX-512 kernels return
  // other bits for the same ray than its AVX2 ones (the golden digests, recorded on an AVX-512 machine,
  // all differed on an AVX2 one). A chain must give the same bytes on every worker of a farm, whatever
  // its CPU, so the kernels are capped at AVX2: every x86-64 CPU since 2013-2015 runs exactly these.
  // (An older CPU without AVX2 gets Embree's SSE/AVX kernels, and other bits.)
  I.device = rtcNewDevice(kDeviceConfig);
  if (!I.device)
    throw std::runtime_error("Embree: cannot create device (error " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
  rtcSetDeviceErrorFunction(I.device, Impl::errorCallback, &I);
  I.scene = rtcNewScene(I.device);
  rtcSetSceneFlags(I.scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(I.scene, RTC_BUILD_QUALITY_HIGH);
  I.check("scene creation");

  I.faceNormals.resize(I.meshes.size());
  for (size_t m = 0; m < I.meshes.size(); ++m) {
    const MeshDesc& mesh = I.meshes[m];
    if (mesh.indices.size() % 3 != 0)
      throw std::runtime_error("mesh '" + mesh.name + "': index count is not a multiple of 3");
    for (uint32_t idx : mesh.indices)
      if (idx >= mesh.positions.size())
        throw std::runtime_error("mesh '" + mesh.name + "': vertex index " + std::to_string(idx) + " out of range (" +
                                 std::to_string(mesh.positions.size()) + " vertices)");
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
      throw std::runtime_error("mesh '" + mesh.name + "': normal count differs from vertex count");
    if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
      throw std::runtime_error("mesh '" + mesh.name + "': uv count differs from vertex count");
    for (const Vec3& p : mesh.positions) bounds_.expand(p);
    if (mesh.indices.empty()) continue;  // nothing to trace; the id stays unused

    RTCGeometry geom = rtcNewGeometry(I.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.positions.size()));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               3 * sizeof(unsigned), mesh.indices.size() / 3));
    if (!v || !idx) {
      rtcReleaseGeometry(geom);
      I.check(("buffer allocation for mesh '" + mesh.name + "'").c_str());
      throw std::runtime_error("Embree: buffer allocation failed for mesh '" + mesh.name + "'");
    }
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
      v[3 * i + 0] = mesh.positions[i].x;
      v[3 * i + 1] = mesh.positions[i].y;
      v[3 * i + 2] = mesh.positions[i].z;
    }
    for (size_t i = 0; i < mesh.indices.size(); ++i) idx[i] = mesh.indices[i];
    std::vector<Impl::FaceNormal>& normals = I.faceNormals[m];
    normals.resize(mesh.indices.size() / 3);
    for (size_t f = 0; f < normals.size(); ++f) {
      const uint32_t* tri = &mesh.indices[3 * f];
      const Vec3& p0 = mesh.positions[tri[0]];
      const Vec3 c = cross(mesh.positions[tri[1]] - p0, mesh.positions[tri[2]] - p0);
      const float len = length(c);
      normals[f] = len > 0 ? Impl::FaceNormal{c / len, true} : Impl::FaceNormal{Vec3(), false};
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(I.scene, geom, static_cast<unsigned>(m));
    if (mesh.convex && mesh.emission) {  // the same geometry, attached to a scene of its own as well
      RTCScene own = rtcNewScene(I.device);
      rtcSetSceneFlags(own, RTC_SCENE_FLAG_ROBUST);
      rtcSetSceneBuildQuality(own, RTC_BUILD_QUALITY_HIGH);
      rtcAttachGeometryByID(own, geom, 0);
      rtcCommitScene(own);
      I.meshScenes.resize(I.meshes.size(), nullptr);
      I.meshScenes[m] = own;
    }
    rtcReleaseGeometry(geom);
    I.check(("geometry of mesh '" + mesh.name + "'").c_str());
  }
  rtcCommitScene(I.scene);
  I.check("scene build");
}

Accel::~Accel() = default;

RayObserver* setThreadRayObserver(RayObserver* observer) {
  RayObserver* previous = tlRayObserver;
  tlRayObserver = observer;
  return previous;
}

namespace {
// Embree's closest hit of `ray` in `scene` (geomID RTC_INVALID_GEOMETRY_ID: a miss), counted by the
// thread's ray observer; intersect, intersectIfOn and intersectMesh differ only in the scene and in
// which hits they complete.
[[gnu::always_inline]] inline RTCRayHit closestHit(RTCScene scene, const Ray& ray) {
  if (tlRayObserver) [[unlikely]] tlRayObserver->closestHit(ray);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh = toRtc(ray);
  rtcIntersect1(scene, &ctx, &rh);
  return rh;
}
}  // namespace

std::optional<SurfaceHit> Accel::intersect(const Ray& ray) const {
  const RTCRayHit rh = closestHit(impl_->scene, ray);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  return impl_->completeHit(ray, rh, rh.hit.geomID);
}

std::optional<SurfaceHit> Accel::intersectIfOn(uint32_t meshId, const Ray& ray) const {
  const RTCRayHit rh = closestHit(impl_->scene, ray);
  if (rh.hit.geomID != meshId) return std::nullopt;  // a miss (RTC_INVALID_GEOMETRY_ID) or another mesh
  return impl_->completeHit(ray, rh, meshId);
}

bool Accel::hasMeshScene(uint32_t meshId) const {
  return meshId < impl_->meshScenes.size() && impl_->meshScenes[meshId];
}

std::optional<SurfaceHit> Accel::intersectMesh(uint32_t meshId, const Ray& ray) const {
  if (!hasMeshScene(meshId)) throw std::logic_error("Accel::intersectMesh: mesh " + std::to_string(meshId) + " has no scene of its own");
  const RTCRayHit rh = closestHit(impl_->meshScenes[meshId], ray);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  return impl_->completeHit(ray, rh, meshId);
}

// The SurfaceHit of Embree's hit on triangle rh.hit.primID of mesh `meshId`, from our copy of the mesh.
SurfaceHit Accel::Impl::completeHit(const Ray& ray, const RTCRayHit& rh, uint32_t meshId) const {
  const MeshDesc& mesh = meshes[meshId];
  const uint32_t* tri = &mesh.indices[3 * size_t(rh.hit.primID)];
  const float u = rh.hit.u, v = rh.hit.v, w = 1 - u - v;

  SurfaceHit h;
  h.t = rh.ray.tfar;
  h.p = ray.o + ray.d * h.t;
  h.meshId = meshId;
  h.primId = rh.hit.primID;
  const FaceNormal& face = faceNormals[meshId][rh.hit.primID];
  h.ng = face.ok ? face.ng : normalize(-ray.d);  // degenerate triangle: face the ray
  h.ns = h.ng;
  if (!mesh.normals.empty()) {
    const Vec3 n = mesh.normals[tri[0]] * w + mesh.normals[tri[1]] * u + mesh.normals[tri[2]] * v;
    const float ln = length(n);
    if (ln > 0 && std::isfinite(ln)) h.ns = faceForward(n / ln, h.ng);
  }
  if (!mesh.uvs.empty()) {
    h.uv = mesh.uvs[tri[0]] * w + mesh.uvs[tri[1]] * u + mesh.uvs[tri[2]] * v;
  } else {
    h.uv = {u, v};
  }
  return h;
}

bool Accel::occluded(const Ray& ray) const {
  if (tlRayObserver) [[unlikely]] tlRayObserver->shadow(ray);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh = toRtc(ray);
  rtcOccluded1(impl_->scene, &ctx, &rh.ray);
  return rh.ray.tfar < 0;  // Embree sets tfar = -inf on a hit
}

}  // namespace mlt
