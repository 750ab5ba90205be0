// Area light over a triangle mesh: uniform by area (a triangle picked through a CDF over areas, then a
// uniform point on it), constant radiance Le emitted on the front side only (dot(w, ng) > 0, ng from the
// counter-clockwise winding), like Mitsuba's `area` emitter. A textured radiance (MeshDesc::emissionTexture)
// is evaluated at the point's uv: the hit's uv in L(), the sampled point's interpolated uv in sampleLi/Le,
// so every technique sees the same Le; sampling stays uniform by area.
#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/bsdf/texture.h"
#include "common/core/sampling.h"
#include "common/emitter/light_factories.h"
#include "common/emitter/make_light.h"
#include "common/scene/scene_desc.h"

namespace mlt {
namespace {

class AreaLight final : public Light {
 public:
  explicit AreaLight(const MeshDesc& mesh);

  std::optional<LightLiSample> sampleLi(const Vec3& ref, Vec2 u) const override;
  float pdfLi(const Vec3& ref, const Vec3& pLight, const Vec3& nLight, const Vec3& wi) const override;
  std::optional<LightLeSample> sampleLe(Vec2 uPos, Vec2 uDir) const override;
  void pdfLe(const Vec3& pLight, const Vec3& nLight, const Vec3& w, float* pdfPos, float* pdfDir) const override;
  Color L(const Vec3& p, const Vec3& n, const Vec2& uv, const Vec3& w) const override {
    return dot(n, w) > 0 ? Le(uv) : Color();
  }
  // Phi = integral over area and hemisphere of Le cos = pi * A * Le (textured: the texture's average).
  Color power() const override { return (tex_ ? tex_->average() : Le_) * (kPi * area_); }

 private:
  struct PointSample {
    Vec3 p, ng;
    Vec2 uv;
  };
  Color Le(Vec2 uv) const { return tex_ ? tex_->eval(uv) : Le_; }
  PointSample samplePoint(Vec2 u) const;

  std::vector<Vec3> v_;        // 3 vertices per triangle
  std::vector<Vec3> ng_;       // unit geometric normal per triangle
  std::vector<double> cdf_;    // size T + 1, cdf_[0] = 0, cdf_[T] = 1
  float area_ = 0;
  Color Le_;
  std::shared_ptr<const Texture> tex_;  // null: constant Le_
  std::vector<Vec2> uv_;                // 3 per triangle, only with a texture
};

AreaLight::AreaLight(const MeshDesc& mesh) {
  if (!mesh.emission) throw std::runtime_error("area light on mesh '" + mesh.name + "': mesh has no emission");
  Le_ = *mesh.emission;
  if (mesh.emissionTexture) {
    tex_ = makeTexture(*mesh.emissionTexture, mesh.name, "area light on mesh");
    const Color m = tex_->maxValue();
    if (!m.isFinite() || tex_->average().r < 0 || tex_->average().g < 0 || tex_->average().b < 0)
      throw std::runtime_error("area light on mesh '" + mesh.name + "': textured radiance must be finite and non-negative");
    Le_ = tex_->average();
  }
  if (!Le_.isFinite() || Le_.r < 0 || Le_.g < 0 || Le_.b < 0)
    throw std::runtime_error("area light on mesh '" + mesh.name + "': radiance must be finite and non-negative");
  if (mesh.indices.size() % 3 != 0)
    throw std::runtime_error("area light on mesh '" + mesh.name + "': index count is not a multiple of 3");
  const size_t nTri = mesh.indices.size() / 3;
  v_.reserve(3 * nTri);
  ng_.reserve(nTri);
  cdf_.assign(nTri + 1, 0.0);
  double total = 0;
  for (size_t i = 0; i < nTri; ++i) {
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t idx = mesh.indices[3 * i + k];
      if (idx >= mesh.positions.size())
        throw std::runtime_error("area light on mesh '" + mesh.name + "': vertex index " + std::to_string(idx) +
                                 " out of range");
      p[k] = mesh.positions[idx];
      v_.push_back(p[k]);
      // Without mesh uvs a hit's uv is its barycentric (u, v) (accel.cpp): vertex k at (0,0), (1,0), (0,1).
      if (tex_) uv_.push_back(mesh.uvs.empty() ? Vec2(k == 1 ? 1.0f : 0.0f, k == 2 ? 1.0f : 0.0f) : mesh.uvs.at(idx));
    }
    const Vec3 c = cross(p[1] - p[0], p[2] - p[0]);
    const float len = length(c);
    ng_.push_back(len > 0 ? c / len : Vec3(0, 0, 1));
    total += 0.5 * double(len);
    cdf_[i + 1] = total;
  }
  if (!(total > 0) || !std::isfinite(total))
    throw std::runtime_error("area light on mesh '" + mesh.name + "': total area is zero or not finite");
  for (double& c : cdf_) c /= total;
  cdf_.back() = 1.0;
  area_ = static_cast<float>(total);
}

// Picks a triangle with probability area_i / A using u.x, remaps u.x to [0,1) within the chosen interval
// (so one 2D sample drives both choices), then a uniform point on the triangle: pdfA = 1 / A.
AreaLight::PointSample AreaLight::samplePoint(Vec2 u) const {
  const size_t nTri = ng_.size();
  size_t i = std::upper_bound(cdf_.begin(), cdf_.end(), double(u.x)) - cdf_.begin();
  i = std::clamp<size_t>(i, 1, nTri) - 1;
  const double w = cdf_[i + 1] - cdf_[i];
  const float ux = w > 0 ? std::clamp(float((double(u.x) - cdf_[i]) / w), 0.0f, kOneMinusEpsilon) : 0.0f;
  const Vec2 b = sampleUniformTriangle({ux, u.y});
  const Vec3* p = &v_[3 * i];
  Vec2 uv;
  if (tex_) {
    const Vec2* t = &uv_[3 * i];
    uv = t[0] * b.x + t[1] * b.y + t[2] * (1 - b.x - b.y);
  }
  return {p[0] * b.x + p[1] * b.y + p[2] * (1 - b.x - b.y), ng_[i], uv};
}

std::optional<LightLiSample> AreaLight::sampleLi(const Vec3& ref, Vec2 u) const {
  const PointSample ps = samplePoint(u);
  Vec3 wi = ps.p - ref;
  const float d2 = lengthSquared(wi);
  if (!(d2 > 0)) return std::nullopt;
  wi = wi / std::sqrt(d2);
  const float cosLight = -dot(wi, ps.ng);
  if (cosLight == 0) return std::nullopt;
  LightLiSample s;
  s.L = cosLight > 0 ? Le(ps.uv) : Color();  // back side: a valid sample that carries nothing
  s.wi = wi;
  s.pLight = ps.p;
  s.nLight = ps.ng;
  s.uv = ps.uv;
  s.pdfA = 1.0f / area_;
  s.pdfW = pdfAToW(s.pdfA, d2, std::fabs(cosLight));  // Veach eq. 8.10
  return s;
}

float AreaLight::pdfLi(const Vec3& ref, const Vec3& pLight, const Vec3& nLight, const Vec3& wi) const {
  return pdfAToW(1.0f / area_, distanceSquared(ref, pLight), absDot(nLight, wi));
}

std::optional<LightLeSample> AreaLight::sampleLe(Vec2 uPos, Vec2 uDir) const {
  const PointSample ps = samplePoint(uPos);
  const Vec3 local = sampleCosineHemisphere(uDir);
  const float pdfDir = cosineHemispherePdfW(local.z);
  if (!(pdfDir > 0)) return std::nullopt;
  LightLeSample s;
  s.L = Le(ps.uv);
  s.ray.o = ps.p;  // the exact point on the light; tMin skips the emitter's own surface
  s.ray.d = normalize(Frame(ps.ng).toWorld(local));
  s.ray.tMin = 1e-4f * std::fmax(1.0f, std::fmax(std::fabs(ps.p.x), std::fmax(std::fabs(ps.p.y), std::fabs(ps.p.z))));
  s.nLight = ps.ng;
  s.uv = ps.uv;
  s.pdfPos = 1.0f / area_;
  s.pdfDir = pdfDir;
  return s;
}

void AreaLight::pdfLe(const Vec3& pLight, const Vec3& nLight, const Vec3& w, float* pdfPos, float* pdfDir) const {
  *pdfPos = 1.0f / area_;
  *pdfDir = cosineHemispherePdfW(dot(nLight, w));
}

}  // namespace

std::unique_ptr<Light> makeAreaLight(const MeshDesc& mesh) { return std::make_unique<AreaLight>(mesh); }

}  // namespace mlt
