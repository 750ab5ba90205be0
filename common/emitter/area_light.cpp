// Area light over a triangle mesh: uniform by area (a triangle picked through a CDF over areas, then a
// uniform point on it), constant radiance Le emitted on the front side only (dot(w, ng) > 0, ng from the
// counter-clockwise winding), like Mitsuba's `area` emitter. A textured radiance (MeshDesc::emissionTexture)
// is evaluated at the point's uv: the hit's uv in L(), the sampled point's interpolated uv in sampleLi/Le,
// so every technique sees the same Le; sampling stays uniform by area.
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
//
// Convex emitters: next-event estimation by solid angle. A sphere light sampled by area wastes half its
// samples on the far side (zero: the point faces away) and weighs the rest by cos / d^2, which varies
// over the near side; pt's direct light on glossy-plates' walls had a coefficient of variation of ~0.3
// from it. For a mesh the front end made convex (MeshDesc::convex: spheres) whose facets all face away
// from its centre, given its own surface as a ray target (EmitterSurface), sampleLi from a point outside
// the mesh's bounding sphere (centre c, radius R, distance d) draws a direction uniformly in the cone of
// half-angle asin(R / d) around c and returns the first point of the mesh along it (none: no sample). A
// convex surface seen from outside shows exactly its facets that face the viewer, each point once, so
//     pdfW(y) = 1 / (2 pi (1 - cos theta_max))   if y's facet faces ref, else 0        (C1)
// whatever the tessellation (the cone's directions that miss the mesh are lost density, not bias). The
// choice between (C1) and the area density depends on ref alone (outside the bounding sphere, with a
// margin), so sampleLi, pdfLi and invertSampleLi always agree. sampleLe (light subpaths) stays by area.
// sampleLiVisible (pt's and bdpt's next-event estimates) finds the same point with one ray through the
// whole scene, which tests its visibility as well (see there).
// bdpt's MIS weight gives the strategy s = 1 this density per unit area (pdfLiOverPdfPos: misWeight's
// factor k). pbrt-v3 keeps the area density there for its sphere lights, which stays unbiased (weights
// that sum to one) but weighs the cone's estimate as if it were area sampling's, so the bidirectional
// methods would hardly gain from the cone (docs/CHAINS.md, "Sphere lights by solid angle").
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/bsdf/texture.h"
#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"
#include "common/emitter/light_factories.h"
#include "common/emitter/make_light.h"
#include "common/scene/scene_desc.h"

namespace mlt {
namespace {

class AreaLight final : public Light {
 public:
  AreaLight(const MeshDesc& mesh, std::shared_ptr<const EmitterSurface> surface);

  std::optional<LightLiSample> sampleLi(const Vec3& ref, Vec2 u) const override;
  std::optional<LightLiSample> sampleLiVisible(const Vec3& ref, const Vec3& ng, Vec2 u) const override;
  float pdfLi(const Vec3& ref, const Vec3& pLight, const Vec3& nLight, const Vec3& wi) const override;
  float pdfLiOverPdfPos(const Vec3& ref, const Vec3& pLight, const Vec3& nLight) const override;
  std::optional<LightLeSample> sampleLe(Vec2 uPos, Vec2 uDir) const override;
  void pdfLe(const Vec3& pLight, const Vec3& nLight, const Vec3& w, float* pdfPos, float* pdfDir) const override;
  Color L(const Vec3& p, const Vec3& n, const Vec2& uv, const Vec3& w) const override {
    return dot(n, w) > 0 ? Le(uv) : Color();
  }
  std::optional<Inverse2D> invertSampleLi(const Vec3& ref, const Vec3& pLight, const Vec3& nLight,
                                          const InverseGamma& gamma) const override;
  std::optional<LightLeInverse> invertSampleLe(const Vec3& pLight, const Vec3& nLight, const Vec3& w,
                                               const InverseGamma& gamma) const override;
  // Phi = integral over area and hemisphere of Le cos = pi * A * Le (textured: the texture's average).
  Color power() const override { return (tex_ ? tex_->average() : Le_) * (kPi * area_); }

 private:
  struct PointSample {
    Vec3 p, ng;
    Vec2 uv;
  };
  Color Le(Vec2 uv) const { return tex_ ? tex_->eval(uv) : Le_; }
  PointSample samplePoint(Vec2 u) const;
  // The cone that ref sees the bounding sphere in (C1), or nullopt: area sampling (no surface, ref inside
  // the bounding sphere or too close to it). The cone's frame is built only where a direction is drawn or
  // inverted (coneFrame): the densities need a and pdfW alone.
  struct Cone {
    Vec3 toCenter;  // boundCenter_ - ref
    float d2;       // |toCenter|^2
    float a;        // 1 - cos(theta_max)
    float pdfW;     // 1 / (2 pi a)
  };
  std::optional<Cone> coneFrom(const Vec3& ref) const;
  static Frame coneFrame(const Cone& cone) { return Frame(cone.toCenter / std::sqrt(cone.d2)); }
  // The ray from ref along the cone's direction for u (sampleLi and sampleLiVisible draw the same one).
  static Ray coneRay(const Vec3& ref, Vec2 u, const Cone& cone) {
    Ray r;
    r.o = ref;
    r.d = normalize(coneFrame(cone).toWorld(sampleUniformConeNarrow(u, cone.a)));
    return r;
  }
  // (C1)'s sample along the unit direction w from ref, given the first hit of the ray from ref on the
  // light's mesh (nullopt: the hit faces away).
  std::optional<LightLiSample> coneSample(const Vec3& ref, const Vec3& w, const SurfaceHit& hit, const Cone& cone) const;
  std::shared_ptr<const EmitterSurface> surface_;  // set only when the cone sampling applies
  Vec3 boundCenter_;
  float boundRadius2_ = 0;
  static constexpr size_t kOneLevelTriangles = 16;
  // Inverse of samplePoint: the u that lands on p (the triangle found by search), or nullopt if p is on
  // no triangle of the mesh.
  std::optional<Vec2> invertPoint(const Vec3& p) const;
  // A uniform grid over the mesh for invertPoint: cell -> triangles whose (slightly expanded) bounds
  // overlap it, in CSR form. Built once in the constructor.
  void buildGrid();
  Bounds3 gridBounds_;
  int gridRes_[3] = {1, 1, 1};
  std::vector<uint32_t> cellStart_, cellTris_;

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
  std::shared_ptr<const Texture> tex_;  // null: constant Le_
  std::vector<Vec2> uv_;                // 3 per triangle, only with a texture
};

AreaLight::AreaLight(const MeshDesc& mesh, std::shared_ptr<const EmitterSurface> surface) {
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
  buildGrid();
  if (surface && mesh.convex) {
    // Bounding sphere about the mesh's box centre; every facet must face away from it (an outward
    // convex surface: flip_normals or a two-sided emitter's back copy faces in and keeps area sampling).
    Bounds3 box;
    for (const Vec3& p : v_) box.expand(p);
    const Vec3 c = box.center();
    double r2 = 0;
    bool outward = true;
    for (size_t i = 0; i < nTri && outward; ++i) {
      const Vec3* p = &v_[3 * i];
      for (int k = 0; k < 3; ++k) r2 = std::max(r2, double(distanceSquared(p[k], c)));
      const bool degenerate = !(lengthSquared(cross(p[1] - p[0], p[2] - p[0])) > 0);  // a pole's sliver
      outward = degenerate || dot(ng_[i], (p[0] + p[1] + p[2]) / 3.0f - c) > 0;
    }
    if (outward && r2 > 0) {
      surface_ = std::move(surface);
      liDensityDiffers_ = true;
      boundCenter_ = c;
      boundRadius2_ = float(r2 * (1 + 1e-5));
    }
  }
}

std::optional<AreaLight::Cone> AreaLight::coneFrom(const Vec3& ref) const {
  if (!surface_) return std::nullopt;
  const Vec3 toCenter = boundCenter_ - ref;
  const float d2 = lengthSquared(toCenter);
  // Outside the bounding sphere by a margin: directions near the cone's edge graze the mesh.
  if (!(d2 > 1.01f * boundRadius2_)) return std::nullopt;
  const float sin2 = boundRadius2_ / d2;
  const float cosMax = std::sqrt(1 - sin2);
  const float a = sin2 / (1 + cosMax);  // = 1 - cosMax without cancellation
  return Cone{toCenter, d2, a, 1 / (2 * kPi * a)};
}

std::optional<LightLiSample> AreaLight::coneSample(const Vec3& ref, const Vec3& w, const SurfaceHit& hit,
                                                   const Cone& cone) const {
  const float cosLight = -dot(w, hit.ng);
  if (!(cosLight > 0)) return std::nullopt;  // grazing: the first hit must face ref (C1)
  LightLiSample s;
  s.L = Le(hit.uv);
  s.wi = w;
  s.pLight = hit.p;
  s.nLight = hit.ng;
  s.uv = hit.uv;
  s.pdfW = cone.pdfW;
  s.pdfA = pdfWToA(cone.pdfW, distanceSquared(ref, hit.p), cosLight);
  return s;
}

void AreaLight::buildGrid() {
  const size_t nTri = ng_.size();
  for (const Vec3& p : v_) gridBounds_.expand(p);
  const Vec3 ext = gridBounds_.hi - gridBounds_.lo;
  const float diag = length(ext), pad = 1e-4f * std::fmax(diag, 1e-6f);
  gridBounds_.lo = gridBounds_.lo - Vec3(pad);
  gridBounds_.hi = gridBounds_.hi + Vec3(pad);
  // About 2 triangles per occupied cell: res ~ (T / 2)^(1/d) along the d axes that have extent.
  const Vec3 size = gridBounds_.hi - gridBounds_.lo;
  const float maxSide = std::fmax(size.x, std::fmax(size.y, size.z));
  int dimsWithExtent = 0;
  for (int a = 0; a < 3; ++a) dimsWithExtent += size[a] > 0.05f * maxSide;
  const double perAxis = std::pow(std::max(1.0, double(nTri) / 2), 1.0 / std::max(1, dimsWithExtent));
  for (int a = 0; a < 3; ++a)
    gridRes_[a] = size[a] > 0.05f * maxSide ? std::clamp(int(perAxis * size[a] / maxSide + 0.5), 1, 128) : 1;
  auto cellRange = [&](const Bounds3& b, int lo[3], int hi[3]) {
    for (int a = 0; a < 3; ++a) {
      const float t0 = (b.lo[a] - gridBounds_.lo[a]) / size[a], t1 = (b.hi[a] - gridBounds_.lo[a]) / size[a];
      lo[a] = std::clamp(int(t0 * gridRes_[a]), 0, gridRes_[a] - 1);
      hi[a] = std::clamp(int(t1 * gridRes_[a]), 0, gridRes_[a] - 1);
    }
  };
  const size_t nCells = size_t(gridRes_[0]) * gridRes_[1] * gridRes_[2];
  std::vector<uint32_t> count(nCells + 1, 0);
  std::vector<Bounds3> triBounds(nTri);
  for (size_t i = 0; i < nTri; ++i) {
    Bounds3 b;
    for (int k = 0; k < 3; ++k) b.expand(v_[3 * i + k]);
    const float maxAbs = std::fmax(std::fmax(std::fabs(b.lo.x), std::fabs(b.hi.x)),
                                   std::fmax(std::fmax(std::fabs(b.lo.y), std::fabs(b.hi.y)),
                                             std::fmax(std::fabs(b.lo.z), std::fabs(b.hi.z))));
    const float triPad = 2e-4f * length(b.hi - b.lo) + 2e-6f * maxAbs + pad;  // covers invertPoint's tolerance
    b.lo = b.lo - Vec3(triPad);
    b.hi = b.hi + Vec3(triPad);
    triBounds[i] = b;
  }
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      cellStart_.assign(nCells + 1, 0);
      for (size_t c = 0; c < nCells; ++c) cellStart_[c + 1] = cellStart_[c] + count[c];
      cellTris_.assign(cellStart_[nCells], 0);
      std::fill(count.begin(), count.end(), 0);
    }
    for (size_t i = 0; i < nTri; ++i) {
      int lo[3], hi[3];
      cellRange(triBounds[i], lo, hi);
      for (int z = lo[2]; z <= hi[2]; ++z)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int x = lo[0]; x <= hi[0]; ++x) {
            const size_t c = (size_t(z) * gridRes_[1] + y) * gridRes_[0] + x;
            if (pass == 1) cellTris_[cellStart_[c] + count[c]] = uint32_t(i);
            ++count[c];
          }
    }
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
  Vec2 uv;
  if (tex_) {
    const Vec2* t = &uv_[3 * i];
    uv = t[0] * b.x + t[1] * b.y + t[2] * (1 - b.x - b.y);
  }
  return {p[0] * b.x + p[1] * b.y + p[2] * (1 - b.x - b.y), ng_[i], uv};
}

std::optional<LightLiSample> AreaLight::sampleLi(const Vec3& ref, Vec2 u) const {
  if (const std::optional<Cone> cone = coneFrom(ref)) {  // (C1)
    const Ray r = coneRay(ref, u, *cone);
    const std::optional<SurfaceHit> hit = surface_->intersect(r);
    if (!hit) return std::nullopt;  // a direction of the cone that misses the mesh
    return coneSample(ref, r.d, *hit, *cone);
  }
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

// (C1) with the light's point and its visibility from one ray through the whole scene. The ray starts at
// ref itself, on the line sampleLi's ray follows, so its first hit on the mesh is sampleLi's point (the
// same facet, the same ray); tMin takes it off ref's surface as far as offsetRayOrigin would (its scale
// h, along the normal), which for a direction at an angle to the surface means h / |cos|, kept at most
// 20 h and short of the light.
std::optional<LightLiSample> AreaLight::sampleLiVisible(const Vec3& ref, const Vec3& ng, Vec2 u) const {
  const std::optional<Cone> cone = coneFrom(ref);
  if (!cone) return sampleLi(ref, u);
  Ray r = coneRay(ref, u, *cone);
  if (ng.x != 0 || ng.y != 0 || ng.z != 0) {
    const float h = rayOffsetScale(ref);
    const float gap = std::sqrt(cone->d2) - std::sqrt(boundRadius2_);  // > 0: ref is outside the sphere
    r.tMin = std::fmin(h / std::fmax(absDot(r.d, ng), 0.05f), 0.5f * gap);
  }
  const std::optional<SurfaceHit> hit = surface_->firstInScene(r);
  if (!hit) return std::nullopt;  // blocked, or a direction of the cone that misses the mesh
  std::optional<LightLiSample> s = coneSample(ref, r.d, *hit, *cone);
  if (s) s->unoccluded = true;
  return s;
}

float AreaLight::pdfLi(const Vec3& ref, const Vec3& pLight, const Vec3& nLight, const Vec3& wi) const {
  if (const std::optional<Cone> cone = coneFrom(ref)) return dot(nLight, wi) < 0 ? cone->pdfW : 0.0f;  // (C1)
  return pdfAToW(1.0f / area_, distanceSquared(ref, pLight), absDot(nLight, wi));
}

// Per unit area at pLight, (C1) is pdfW cos / d^2; by area it is 1 / A, the same as sampleLe's pdfPos.
float AreaLight::pdfLiOverPdfPos(const Vec3& ref, const Vec3& pLight, const Vec3& nLight) const {
  const std::optional<Cone> cone = coneFrom(ref);
  if (!cone) return 1.0f;
  const Vec3 w = pLight - ref;
  const float d2 = lengthSquared(w);
  const float cosLight = -dot(w, nLight);
  if (!(d2 > 0) || !(cosLight > 0)) return 0.0f;
  return pdfWToA(cone->pdfW, d2, cosLight / std::sqrt(d2)) * area_;
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
  s.ray.tMin = rayOffsetScale(ps.p);
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

// ---- Inverses (reversible-jump MLT; interfaces/inverse.h) ---------------------------------------------

// The triangle holding p is found by a linear search (the one with the smallest distance to p, counting
// distance off the plane and outside the edges; a point on a shared edge may go to either, a set of
// measure zero). samplePoint's u.x picks the triangle through the CDF and is remapped inside the chosen
// interval, so u.x = cdf_i + w_i ux is one-to-one (no ambiguity), and b0 = 1 - sqrt(ux), b1 = uy sqrt(ux);
// with two levels u.x picks the group and u.y the triangle in it, each remapped the same way.
// Jacobian (per unit area): (area_i / A) * (1 / area_i) = 1 / A.
std::optional<Vec2> AreaLight::invertPoint(const Vec3& p) const {
  const size_t nTri = ng_.size();
  size_t best = nTri;
  double bestErr = 0, bestB0 = 0, bestB1 = 0;
  // The grid cell of p lists every triangle whose expanded bounds contain p.
  size_t cell = 0;
  for (int a = 2; a >= 0; --a) {
    const float extent = gridBounds_.hi[a] - gridBounds_.lo[a];
    const float t = extent > 0 ? (p[a] - gridBounds_.lo[a]) / extent : 0.0f;
    if (!(t >= 0 && t <= 1)) return std::nullopt;  // off the mesh's bounds
    cell = cell * gridRes_[a] + std::clamp(int(t * gridRes_[a]), 0, gridRes_[a] - 1);
  }
  for (uint32_t ci = cellStart_[cell]; ci < cellStart_[cell + 1]; ++ci) {
    const size_t i = cellTris_[ci];
    const Vec3* v = &v_[3 * i];
    const double e0[3] = {double(v[1].x) - v[0].x, double(v[1].y) - v[0].y, double(v[1].z) - v[0].z};
    const double e1[3] = {double(v[2].x) - v[0].x, double(v[2].y) - v[0].y, double(v[2].z) - v[0].z};
    const double d[3] = {double(p.x) - v[0].x, double(p.y) - v[0].y, double(p.z) - v[0].z};
    auto dt = [](const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    const double d00 = dt(e0, e0), d01 = dt(e0, e1), d11 = dt(e1, e1), d20 = dt(d, e0), d21 = dt(d, e1);
    const double den = d00 * d11 - d01 * d01;
    if (!(den > 0)) continue;
    const double b1 = (d11 * d20 - d01 * d21) / den, b2 = (d00 * d21 - d01 * d20) / den, b0 = 1 - b1 - b2;
    const double size = std::sqrt(std::max(d00, d11));
    const double n[3] = {double(ng_[i].x), double(ng_[i].y), double(ng_[i].z)};
    const double off = std::fabs(dt(d, n));
    // Distance off the triangle relative to its size, over what float coordinates of p's magnitude allow
    // (a tiny triangle far from the origin: 0.002 wide at |p| = 5 is 1.5e-4 of its size per float ulp).
    const double maxAbs = std::max({std::fabs(double(p.x)), std::fabs(double(p.y)), std::fabs(double(p.z))});
    const double err = (off / size + std::max({0.0, -b0, -b1, -b2})) / (1e-4 + 1e-6 * maxAbs / size);
    if (best == nTri || err < bestErr) {
      best = i;
      bestErr = err;
      bestB0 = b0;
      bestB1 = b1;
    }
  }
  if (best == nTri || !(bestErr <= 1)) return std::nullopt;
  const Vec2 ut = invertUniformTriangle(std::clamp(bestB0, 0.0, 1.0), std::clamp(bestB1, 0.0, 1.0));
  // The remainder r in [0, 1) of a choice placed back inside the chosen interval [lo, hi) of its CDF.
  const auto place = [](double lo, double hi, float r) -> std::optional<float> {
    if (!(hi > lo)) return std::nullopt;
    float v = static_cast<float>(lo + double(r) * (hi - lo));
    while (double(v) >= hi && v > 0) v = std::nextafter(v, 0.0f);  // stay in the interval
    while (double(v) < lo) v = std::nextafter(v, 1.0f);
    return clampPrimary(v);
  };
  if (groupSize_ == 0) {  // one level: u.x = the triangle's interval, remainder ut.x; u.y = ut.y
    const std::optional<float> ux = place(cdf_[best], cdf_[best + 1], ut.x);
    if (!ux) return std::nullopt;
    return Vec2(*ux, ut.y);
  }
  // Two levels: u.x in the group's interval (remainder ut.x), u.y in the triangle's interval within its
  // group (remainder ut.y); a group's last triangle ends at 1 (see samplePoint).
  const size_t g = best / groupSize_;
  const size_t groupEnd = std::min(ng_.size(), (g + 1) * groupSize_);
  const std::optional<float> ux = place(groupCdf_[g], groupCdf_[g + 1], ut.x);
  const std::optional<float> uy = place(cdf_[best], best + 1 < groupEnd ? cdf_[best + 1] : 1.0, ut.y);
  if (!ux || !uy) return std::nullopt;
  return Vec2(*ux, *uy);
}

std::optional<Inverse2D> AreaLight::invertSampleLi(const Vec3& ref, const Vec3& pLight, const Vec3& nLight,
                                                   const InverseGamma&) const {
  const float d2 = distanceSquared(ref, pLight);
  if (!(d2 > 0)) return std::nullopt;
  if (const std::optional<Cone> cone = coneFrom(ref)) {  // (C1): the direction's place in the cone
    const Vec3 w = (pLight - ref) / std::sqrt(d2);
    const float cosLight = -dot(w, nLight);
    if (!(cosLight > 0)) return std::nullopt;
    const std::optional<Vec2> u = invertUniformConeNarrow(coneFrame(*cone).toLocal(w), cone->a);
    if (!u) return std::nullopt;
    return Inverse2D{*u, pdfWToA(cone->pdfW, d2, cosLight)};
  }
  const std::optional<Vec2> u = invertPoint(pLight);
  if (!u) return std::nullopt;
  return Inverse2D{*u, 1.0f / area_};
}

// The direction was drawn cosine-weighted about the triangle's normal: its local (x, y) is the disk point.
std::optional<LightLeInverse> AreaLight::invertSampleLe(const Vec3& pLight, const Vec3&, const Vec3& w,
                                                        const InverseGamma&) const {
  const std::optional<Vec2> u = invertPoint(pLight);
  if (!u) return std::nullopt;
  const Vec3 ng = samplePoint(*u).ng;
  const Vec3 local = Frame(ng).toLocal(normalize(w));
  const float pdfDir = cosineHemispherePdfW(local.z);
  if (!(pdfDir > 0)) return std::nullopt;
  LightLeInverse inv;
  inv.pos = Inverse2D{*u, 1.0f / area_};
  inv.dir = Inverse2D{invertCosineHemisphere(local), pdfDir};
  return inv;
}

}  // namespace

std::unique_ptr<Light> makeAreaLight(const MeshDesc& mesh, std::shared_ptr<const EmitterSurface> surface) {
  return std::make_unique<AreaLight>(mesh, std::move(surface));
}

}  // namespace mlt
