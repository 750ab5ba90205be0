// Veach's bidirectional mutation (Veach 1997, sec. 11.4.2; the CMU lecture's notation).
//
// Deletion: kd = m - l edges with probability pd1[kd] (pd1[1] = 0.25, pd1[2] = 0.5, pd1[j] = 2^-j for
// j >= 3, normalized over kd in [1, k + 2]), then l uniform over the positions with l in [-1, k-1] and
// m = l + kd in [1, k + 1] (pd2[l | kd]); x_{l+1} .. x_{m-1} are deleted (l = -1 deletes the light
// vertex, m = k + 1 the lens vertex).
// Addition: ka edges with probability pa1[ka | kd] (pa1[kd] = 0.5, pa1[kd +- 1] = 0.15,
// pa1[kd +- j] = 0.2 * 2^-j for j >= 2), normalized over ka in [kaMin, kaMax]: kaMin = 1 + [l = -1] +
// [m = k + 1] (a deleted endpoint must be made again) and kaMax keeps k' = k - kd + ka <= max depth. The
// ka - 1 new vertices split into l' from the light side and m' from the eye side, l' uniform over the
// allowed values: a new lens vertex needs m' >= 1; a kept lens vertex (m = k) takes m' = 0 (it is
// connected to, never traced from). The two sides are then joined by a deterministic connection, or,
// when there is no light side at all (l = -1, l' = 0), the eye side must end on an emitter.
// Both sides follow Dirac lobes (the kept end x_l excepted: it stays non-specular); a specular run traced
// from the light side has its density converted to the canonical measure (path.h lightChainToCanonical).
// A point or spot light (path.h) is re-sampled only by the light side (density pmf, direction by its
// sampleLe); the splits in which the eye side would end on it have density 0 (eyeStep).
//
// Transition density (the lecture's g(x -> y)):
//     T(x -> y) = sum over (l, m) whose kept parts x_0..x_l, x_m..x_k are y's ends
//                   pd[l, m] pa1[ka | kd] / #l'  sum over allowed l'  p_light(z_1..z_l') p_eye(z_ka-1..z_l'+1),
// with p_light / p_eye the products of PathSpace::lightStep / eyeStep over the new vertices (canonical
// measure, path.h; the light side's specular runs converted).
#include <algorithm>
#include <cmath>

#include "common/core/sampling.h"
#include "common/methods/veach/mutations.h"
#include "common/render/render_scene.h"

namespace mlt::veach {

namespace {

double pd1Weight(int kd) { return kd == 1 ? 0.25 : kd == 2 ? 0.5 : std::ldexp(1.0, -kd); }
double pa1Weight(int ka, int kd) {
  const int j = std::abs(ka - kd);
  return j == 0 ? 0.5 : j == 1 ? 0.15 : 0.2 * std::ldexp(1.0, -j);
}

struct Range {
  int lo, hi;
  int count() const { return hi >= lo ? hi - lo + 1 : 0; }
};
// Positions l for a deletion of kd edges from a path of k edges.
Range lRange(int kd, int k) { return {std::max(-1, 1 - kd), std::min(k - 1, k + 1 - kd)}; }
// Allowed light-side counts l' for nZ new vertices.
Range lpRange(int nZ, int m, int k) {
  if (m == k) return {nZ, nZ};
  if (m == k + 1) return {0, nZ - 1};
  return {0, nZ};
}

class BidirMutation final : public Mutation {
 public:
  explicit BidirMutation(const PathSpace& space) : space_(space) {}

  bool applicable(const Path& x) const override { return x.k() >= 1; }

  // pd[l, m] = pd1[kd] / #l.
  static double pd(int kd, int k) {
    double sum = 0;
    for (int j = 1; j <= k + 2; ++j) sum += pd1Weight(j);
    return pd1Weight(kd) / sum / double(lRange(kd, k).count());
  }
  static double pa(int ka, int kd, int kaMin, int kaMax) {
    if (ka < kaMin || ka > kaMax) return 0;
    double sum = 0;
    for (int j = kaMin; j <= kaMax; ++j) sum += pa1Weight(j, kd);
    return pa1Weight(ka, kd) / sum;
  }

  bool propose(const Path& x, Pcg32& rng, Path& y) const override {
    const int k = x.k();
    const RenderScene& scene = space_.scene();
    // ---- deletion ----
    double sum = 0;
    for (int j = 1; j <= k + 2; ++j) sum += pd1Weight(j);
    double u = rng.uniformDouble() * sum;
    int kd = 1;
    for (; kd < k + 2 && u >= pd1Weight(kd); ++kd) u -= pd1Weight(kd);
    const Range lr = lRange(kd, k);
    const int l = lr.lo + int(rng.bounded(uint32_t(lr.count())));
    const int m = l + kd;
    // ---- addition ----
    const int kaMin = 1 + (l == -1) + (m == k + 1), kaMax = space_.maxEdges() - (k - kd);
    if (kaMin > kaMax) return false;
    double paSum = 0;
    for (int j = kaMin; j <= kaMax; ++j) paSum += pa1Weight(j, kd);
    u = rng.uniformDouble() * paSum;
    int ka = kaMin;
    for (; ka < kaMax && u >= pa1Weight(ka, kd); ++ka) u -= pa1Weight(ka, kd);
    const int nZ = ka - 1;
    const Range lp = lpRange(nZ, m, k);
    if (lp.count() == 0) return false;
    const int lPrime = lp.lo + int(rng.bounded(uint32_t(lp.count())));
    const int mPrime = nZ - lPrime;
    // A kept end that becomes a connection end must be connectible: y's f evaluates its BSDF off any Dirac
    // lobe, which for a mirror or glass (Bsdf::isDelta) is zero, so such a y is rejected whatever would be
    // traced; reject it before tracing. (x_l connects when the light side adds no vertex, x_m when the eye
    // side adds none; extending from a Dirac x_l already stops at its first sampled direction below.)
    const auto deltaOnly = [&](int i) { return x.v[i].specular && x.v[i].bsdf && x.v[i].bsdf->isDelta(); };
    if (lPrime == 0 && l >= 0 && deltaOnly(l)) return false;
    if (mPrime == 0 && m >= 1 && m <= k - 1 && (l >= 0 || lPrime > 0) && deltaOnly(m)) return false;

    // ---- light side: x_0..x_l, then l' vertices ----
    y.v.assign(x.v.begin(), x.v.begin() + (l + 1));
    if (l >= 0) y.v[l].specular = false;
    for (int j = 0; j < lPrime; ++j) {
      PathVertex nv;
      if (y.v.empty()) {
        float pmf = 0;
        const int index = scene.lightSampler().sample(rng.uniform(), &pmf);
        if (index < 0 || !(pmf > 0)) return false;
        const std::optional<LightLeSample> le = scene.light(index).sampleLe(rng.uniform2(), Vec2(0.5f, 0.5f));
        if (!le) return false;
        nv.kind = VertexKind::Light;
        nv.p = le->ray.o;
        nv.ng = nv.ns = le->nLight;
        nv.light = &scene.light(index);
        nv.lightIndex = index;
      } else {
        Vec3 w;
        const PathVertex& from = y.v.back();
        if (y.v.size() == 1 && from.light->deltaPosition()) {
          // Emission from a point or spot light: its own sampleLe direction (pdfLe's pdfDir; the position
          // is the light's, whatever uPos).
          const std::optional<LightLeSample> le = from.light->sampleLe(Vec2(0.5f, 0.5f), rng.uniform2());
          if (!le || le->L.isBlack() || !(le->pdfDir > 0)) return false;
          w = le->ray.d;
        } else if (y.v.size() == 1) {
          // Emission: cosine-weighted about the light's normal, as AreaLight::sampleLe (pdfLe's pdfDir).
          const Vec3 local = sampleCosineHemisphere(rng.uniform2());
          if (!(local.z > 0)) return false;
          w = normalize(Frame(from.ng).toWorld(local));
        } else {
          const std::optional<BsdfSample> bs = sampleDirection(from, y.v[y.v.size() - 2], TransportMode::Importance, rng, &w);
          if (!bs) return false;
          if (bs->delta) {
            if (int(y.v.size()) - 1 == l) return false;  // the kept end x_l stays non-specular
            y.v.back().specular = true;
          }
        }
        const std::optional<PathVertex> hit = space_.trace(from.p, from.ng, w);
        if (!hit) return false;
        nv = *hit;
      }
      y.v.push_back(nv);
    }

    // ---- eye side: x_k..x_m (eye first), then m' vertices ----
    thread_local std::vector<PathVertex> eye;  // scratch: no allocation per proposal once grown
    eye.assign(x.v.rbegin(), x.v.rbegin() + (k - m + 1));
    Vec2 uLens = x.uLens;
    Vec3 cameraDir;
    for (int j = 0; j < mPrime; ++j) {
      if (eye.empty()) {
        const Camera& cam = scene.camera();
        const Vec2 raster(rng.uniform() * float(cam.width()), rng.uniform() * float(cam.height()));
        uLens = rng.uniform2();
        eye.push_back(space_.cameraVertex(raster, uLens, &cameraDir));
        continue;
      }
      PathVertex& from = eye.back();
      std::optional<PathVertex> hit;
      if (from.kind == VertexKind::Camera) {
        hit = space_.trace(from.p, Vec3(), cameraDir);
      } else {
        Vec3 w;
        const std::optional<BsdfSample> bs = sampleDirection(from, eye[eye.size() - 2], TransportMode::Radiance, rng, &w);
        if (!bs) return false;
        from.specular = bs->delta;
        hit = space_.trace(from.p, from.ng, w);
      }
      if (!hit) return false;
      eye.push_back(*hit);
    }
    if (eye.back().kind == VertexKind::Surface) eye.back().specular = false;  // the connection end
    if (y.v.empty()) {
      // No light side: the eye side ends on an emitter (x_0).
      if (!space_.makeLightVertex(eye.back())) return false;
    }
    y.v.insert(y.v.end(), eye.rbegin(), eye.rend());
    y.uLens = uLens;
    return y.k() >= 1 && y.k() <= space_.maxEdges() && y.v.back().kind == VertexKind::Camera;
  }

  double density(const Path& x, const Path& y) const override {
    const int kx = x.k(), ky = y.k();
    if (kx < 1 || ky < 1) return 0;
    int prefix = 0;  // leading vertices shared by x and y
    while (prefix <= std::min(kx, ky) && x.v[prefix].samePoint(y.v[prefix])) ++prefix;
    int suffix = 0;  // trailing vertices shared
    while (suffix <= std::min(kx, ky) && x.v[kx - suffix].samePoint(y.v[ky - suffix])) ++suffix;
    // A new vertex coincides with a deleted one with probability 0, so the kept parts are exactly the
    // shared ones: l = prefix - 1 and m = kx - suffix + 1. Summing over shorter kept parts as well would
    // add densities of a higher dimension (a kept vertex counted as regenerated): veach_density_test
    // measured T 15-20% too high that way. The one exception is a pinhole's lens point, which a new lens
    // vertex reproduces exactly: with only the lens point shared, m = kx + 1 (lens regenerated) also counts.
    // Likewise at the other end a point or spot light, which a new light vertex reproduces with probability
    // pmf: with only x_0 shared on such a light, l = -1 (light regenerated) also counts.
    if (prefix + suffix > std::min(kx, ky) + 1) return 0;  // y = x (the identity proposal; see veach_chain.cpp)
    int lCandidates[2] = {prefix - 1, -2};
    if (prefix == 1 && isDeltaPositionLight(x.v[0])) lCandidates[1] = -1;
    int mCandidates[2] = {kx - suffix + 1, -1};
    if (suffix == 1 && space_.scene().camera().deltaPosition()) mCandidates[1] = kx + 1;
    double total = 0;
    for (const int l : lCandidates) {
      if (l < -1 || l > kx - 1) continue;
      for (const int m : mCandidates) {
        if (m < std::max(l + 1, 1) || m > kx + 1) continue;
        const int nB = kx - m + 1;
        if (nB > suffix) continue;
        const int nZ = (ky + 1) - (l + 1) - nB;
        if (nZ < 0) continue;
        const int kd = m - l, ka = nZ + 1;
        const int kaMin = 1 + (l == -1) + (m == kx + 1), kaMax = space_.maxEdges() - (kx - kd);
        const double pTerm = pd(kd, kx) * pa(ka, kd, kaMin, kaMax);
        if (!(pTerm > 0)) continue;
        if (l >= 0 && y.v[l].specular) continue;  // the light side's end extends or connects: non-specular
        const Range lp = lpRange(nZ, m, kx);
        for (int lPrime = lp.lo; lPrime <= lp.hi; ++lPrime) {
          double dens = pTerm / double(lp.count());
          // Light side: y_{l+1} .. y_{l+l'} (its end, the connection, non-specular); each specular run
          // it traced is converted from the light-free to the canonical measure.
          if (lPrime > 0 && y.v[l + lPrime].specular) dens = 0;
          for (int i = l + 1; i <= l + lPrime && dens > 0; ++i) dens *= space_.lightStep(y, i);
          for (int i = l + 1; i < l + lPrime && dens > 0;) {
            if (!y.v[i].specular) {
              ++i;
              continue;
            }
            int r1 = i;
            while (y.v[r1 + 1].specular) ++r1;
            dens *= lightChainToCanonical(y, i, r1);
            i = r1 + 1;
          }
          // Eye side: y_{ky-nB} down to y_{l+l'+1}, each from its eye-side neighbour; a new lens vertex
          // first (nB = 0).
          const int eyeLo = l + lPrime + 1;
          int eyeHi = ky - nB;
          if (nB == 0 && eyeHi >= eyeLo) {
            dens *= space_.lensDensity();
            --eyeHi;
          }
          for (int i = eyeHi; i >= eyeLo && dens > 0; --i) dens *= space_.eyeStep(y, i);
          // The connection's ends are non-specular (a kept x_m, or the last eye vertex).
          if (dens > 0 && (l >= 0 || lPrime > 0) && eyeLo <= ky && y.v[eyeLo].kind == VertexKind::Surface &&
              y.v[eyeLo].specular)
            dens = 0;
          total += dens;
        }
      }
    }
    return total;
  }

 private:
  const PathSpace& space_;
};

}  // namespace

std::unique_ptr<Mutation> makeBidirMutation(const PathSpace& space) { return std::make_unique<BidirMutation>(space); }

}  // namespace mlt::veach
