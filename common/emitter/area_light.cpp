// Area light over a triangle mesh: uniform by area (a triangle picked through a CDF over areas, then a
// uniform point on it), constant radiance Le emitted on the front side only (dot(w, ng) > 0, ng from the
// counter-clockwise winding), like Mitsuba's `area` emitter.
//
// Locality of the position sample (Markov chains). A mesh of more than kOneLevelTriangles triangles picks
// its triangle in two levels: u.x a group of about sqrt(T) consecutive triangles (mesh order), u.y a
// triangle inside the group, each by area through its CDF, and both remainders the point on the triangle.
// The density is the same (area_i / A, uniform on the triangle); what changes is that a triangle owns an
// interval of ~1/sqrt(T) in each coordinate instead of ~1/T in u.x alone. With one level a 16k-facet
// sphere light gave every facet ~6e-5 of u.x, far below the smallest small step of the Kelemen kernel
// (1/1024): every small step moved the light point ~16 facets away, and with it the facet normal that
// the emitted direction is sampled around, so a chain on a light path through a sharp glossy lobe could
// not make a single local move and stayed stuck (glossy-plates, tests/mlt_stuck_test.cpp).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

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
    return dot(n, w) > 0 ? Le_ : Color();
  }
  // Phi = integral over area and hemisphere of Le cos = pi * A * Le.
  Color power() const override { return Le_ * (kPi * area_); }

 private:
  struct PointSample {
    Vec3 p, ng;
  };
  PointSample samplePoint(Vec2 u) const;
  static constexpr size_t kOneLevelTriangles = 16;

  std::vector<Vec3> v_;        // 3 vertices per triangle
  std::vector<Vec3> ng_;       // unit geometric normal per triangle
  std::vector<double> cdf_;    // size T + 1, cdf_[0] = 0, cdf_[T] = 1
  // Two levels (T > kOneLevelTriangles): group g holds triangles [g * groupSize_, (g + 1) * groupSize_);
  // groupCdf_ over groups by area (size G + 1); cdf_ is then the CDF within each triangle's group
  // (cdf_[first of group] = 0, cdf_[end of group] = 1).
  size_t groupSize_ = 0;
  std::vector<double> groupCdf_;
  float area_ = 0;
  Color Le_;
};

AreaLight::AreaLight(const MeshDesc& mesh) {
  if (!mesh.emission) throw std::runtime_error("area light on mesh '" + mesh.name + "': mesh has no emission");
  Le_ = *mesh.emission;
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
    }
    const Vec3 c = cross(p[1] - p[0], p[2] - p[0]);
    const float len = length(c);
    ng_.push_back(len > 0 ? c / len : Vec3(0, 0, 1));
    total += 0.5 * double(len);
    cdf_[i + 1] = total;
  }
  if (!(total > 0) || !std::isfinite(total))
    throw std::runtime_error("area light on mesh '" + mesh.name + "': total area is zero or not finite");
  area_ = static_cast<float>(total);
  for (double& c : cdf_) c /= total;
  cdf_.back() = 1.0;
  if (nTri > kOneLevelTriangles) {
    // cdf_[i] becomes the CDF at the start of triangle i within its group (0 for a group's first triangle;
    // a group's end counts as 1), groupCdf_ the CDF over groups.
    groupSize_ = size_t(std::ceil(std::sqrt(double(nTri))));
    const size_t groups = (nTri + groupSize_ - 1) / groupSize_;
    groupCdf_.assign(groups + 1, 0.0);
    std::vector<double> within(nTri + 1, 1.0);
    for (size_t g = 0; g < groups; ++g) {
      const size_t first = g * groupSize_, end = std::min(nTri, first + groupSize_);
      const double groupArea = cdf_[end] - cdf_[first];
      groupCdf_[g + 1] = cdf_[end];
      for (size_t i = first; i < end; ++i) within[i] = groupArea > 0 ? (cdf_[i] - cdf_[first]) / groupArea : 0.0;
    }
    groupCdf_.back() = 1.0;
    cdf_ = std::move(within);
  }
}

// Picks a triangle with probability area_i / A using u.x, remaps u.x to [0,1) within the chosen interval
// (so one 2D sample drives both choices), then a uniform point on the triangle: pdfA = 1 / A.
// Two levels (see the top): u.x picks the group, u.y the triangle in it; the remainders place the point.
AreaLight::PointSample AreaLight::samplePoint(Vec2 u) const {
  const size_t nTri = ng_.size();
  // Index i in [lo, hi) whose CDF interval [cdf[i], cdf[i + 1]) holds v (cdf[lo] = 0; the end counts as 1,
  // whatever cdf[hi] holds), and v remapped to [0, 1) within it.
  const auto pick = [](const std::vector<double>& cdf, size_t lo, size_t hi, float v, float* rest) {
    const size_t i = size_t(std::upper_bound(cdf.begin() + lo + 1, cdf.begin() + hi, double(v)) - cdf.begin()) - 1;
    const double end = i + 1 < hi ? cdf[i + 1] : 1.0;
    const double w = end - cdf[i];
    *rest = w > 0 ? std::clamp(float((double(v) - cdf[i]) / w), 0.0f, kOneMinusEpsilon) : 0.0f;
    return i;
  };
  float ux = 0, uy = u.y;
  size_t i = 0;
  if (groupSize_ == 0) {
    i = pick(cdf_, 0, nTri, u.x, &ux);
  } else {
    const size_t g = pick(groupCdf_, 0, groupCdf_.size() - 1, u.x, &ux);
    const size_t first = g * groupSize_, end = std::min(nTri, first + groupSize_);
    i = pick(cdf_, first, end, u.y, &uy);
  }
  const Vec2 b = sampleUniformTriangle({ux, uy});
  const Vec3* p = &v_[3 * i];
  return {p[0] * b.x + p[1] * b.y + p[2] * (1 - b.x - b.y), ng_[i]};
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
  s.L = cosLight > 0 ? Le_ : Color();  // back side: a valid sample that carries nothing
  s.wi = wi;
  s.pLight = ps.p;
  s.nLight = ps.ng;
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
  s.L = Le_;
  s.ray.o = ps.p;  // the exact point on the light; tMin skips the emitter's own surface
  s.ray.d = normalize(Frame(ps.ng).toWorld(local));
  s.ray.tMin = 1e-4f * std::fmax(1.0f, std::fmax(std::fabs(ps.p.x), std::fmax(std::fabs(ps.p.y), std::fabs(ps.p.z))));
  s.nLight = ps.ng;
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
