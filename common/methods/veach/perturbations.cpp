// Veach's lens and caustic perturbations (Veach 1997, sec. 11.4.3; Veach and Guibas 1997, sec. 5.3).
//
// Lens perturbation, paths E S* D (D|L): with m = eyeChainEnd(x) (x_{k-1} .. x_{m+1} specular, x_m not,
// and x_{m-1} non-specular), the film position moves by R (cos phi, sin phi), R = r2 exp(-ln(r2/r1) u),
// phi uniform; the lens point is kept (thin lens: the same lens sample). The new camera ray follows the
// same lobes (reflect / transmit) through the chain, must hit a non-Dirac surface as y_m, and y_m is
// connected to the kept x_{m-1}. The step's density per unit film area,
//     p_R(|d|) / (2 pi |d|),  p_R(R) = 1 / (R ln(r2 / r1)),
// is symmetric in x and y; the camera maps film area to directions with density pdfDir (raster uniform
// over the W x H film: W H pdfDir per pixel^2), and the chain is deterministic, so in the canonical
// measure (path.h; eye-free: the lens point and the first vertex after it are free)
//     T(x -> y) = p_R(|d|) / (2 pi |d|) * W H * pdfDir(y) |cos y_{k-1}| / |y_k - y_{k-1}|^2.
//
// Caustic perturbation, paths (D|L) S* D E: x_{k-1} non-specular, x_{k-2} .. x_{j+1} specular, x_j not.
// The direction leaving x_j toward x_{j+1} turns by theta = theta2 exp(-ln(theta2/theta1) u) about a
// uniform axis; the same lobes are followed toward the eye, the hit must be a non-Dirac surface y_{k-1},
// which is connected to the kept lens point. The angular density per steradian,
//     p_w = p_theta(theta) / (2 pi sin theta),
// is symmetric. The move generates the chain from its light end (the "light-free" parametrization:
// x_j and the direction are free, a = y_{k-1} determined). By conservation of etendue along a specular
// chain, G(a, s_1) dA(a) dA(s_1) = G(s_m, v) dA(s_m) dA(v) (same medium at both ends, v = x_j), which
// turns the density into the canonical measure:
//     T(x -> y) = p_w * G(y_{k-1}, y_{k-2}) / |cos_{y_j}(w)|,
// (for an empty chain, j = k - 2: p_w |cos y_{k-1}| / d^2, the plain solid angle to area conversion),
// times a shading-normal factor per specular vertex (path.h lightChainToCanonical).
#include <cmath>

#include "common/methods/veach/mutations.h"
#include "common/render/render_scene.h"

namespace mlt::veach {

namespace {

bool sameKeptPoints(const Path& x, const Path& y, int upTo) {
  for (int i = 0; i <= upTo; ++i)
    if (!x.v[i].samePoint(y.v[i])) return false;
  return true;
}

// The specular vertices (from, to) of y follow x's lobes and are specular.
bool sameChain(const Path& x, const Path& y, int from, int to) {
  for (int i = from; i <= to; ++i)
    if (!y.v[i].specular || !x.v[i].specular || transmits(x, i) != transmits(y, i)) return false;
  return true;
}

class LensPerturbation final : public Mutation {
 public:
  LensPerturbation(const PathSpace& space, double r1, double r2) : space_(space), r1_(r1), r2_(r2) {}

  bool applicable(const Path& x) const override {
    const int m = eyeChainEnd(x);
    return m >= 1 && !x.v[m - 1].specular;
  }

  bool propose(const Path& x, Pcg32& rng, Path& y) const override {
    const int k = x.k(), m = eyeChainEnd(x);
    const std::optional<Vec2> raster = perturbRaster(space_, x, rng, r1_, r2_);
    if (!raster) return false;
    y = x;
    Vec3 dir;
    y.v[k] = space_.cameraVertex(*raster, x.uLens, &dir);
    return retraceSpecularChain(space_, x, y, k - 1, m, -1, dir, TransportMode::Radiance);
  }

  double density(const Path& x, const Path& y) const override {
    const int k = x.k(), m = eyeChainEnd(x);
    if (y.k() != k || m < 1 || eyeChainEnd(y) != m || !applicable(y)) return 0;
    if (!sameKeptPoints(x, y, m - 1) || !x.v[k].samePoint(y.v[k]) || !sameChain(x, y, m + 1, k - 1)) return 0;
    return filmStepDensity(space_, x, y, r1_, r2_);
  }

 private:
  const PathSpace& space_;
  double r1_, r2_;
};

// x_j for the caustic perturbation, or -1 if x is not (D|L) S* D E.
int causticSource(const Path& x) {
  const int k = x.k();
  if (k < 2 || x.v[k - 1].specular || x.v[k - 1].kind != VertexKind::Surface) return -1;
  for (int i = k - 2; i >= 0; --i)
    if (!x.v[i].specular) return i;
  return -1;
}

class CausticPerturbation final : public Mutation {
 public:
  CausticPerturbation(const PathSpace& space, double theta1, double theta2)
      : space_(space), theta1_(theta1), theta2_(theta2) {}

  bool applicable(const Path& x) const override { return causticSource(x) >= 0; }

  bool propose(const Path& x, Pcg32& rng, Path& y) const override {
    const int k = x.k(), j = causticSource(x);
    const Vec3 dir = perturbDirection(x, j, j + 1, rng, theta1_, theta2_);
    y = x;
    return retraceSpecularChain(space_, x, y, j + 1, k - 1, +1, dir, TransportMode::Importance);
  }

  double density(const Path& x, const Path& y) const override {
    const int k = x.k(), j = causticSource(x);
    if (y.k() != k || j < 0 || causticSource(y) != j) return 0;
    if (!sameKeptPoints(x, y, j) || !x.v[k].samePoint(y.v[k]) || !sameChain(x, y, j + 1, k - 2)) return 0;
    const Vec3 wx = normalize(x.v[j + 1].p - x.v[j].p), wy = normalize(y.v[j + 1].p - y.v[j].p);
    const double c = dot(wx, wy), s = length(cross(wx, wy));
    const double theta = std::atan2(s, c);
    const double pW = exponentialStepDensity(theta, theta1_, theta2_) / (2 * M_PI * std::sin(theta));
    const double cosV = PathSpace::cosAt(y.v[j], wy);
    if (!(cosV > 0)) return 0;
    // Light-free density p_w G(v, s_m) / |cos_v| (s_m = y_{j+1}), converted to the canonical measure.
    const double lightFree = pW * geometry(y.v[j], y.v[j + 1]) / cosV;
    return j + 1 <= k - 2 ? lightFree * lightChainToCanonical(y, j + 1, k - 2) : lightFree;
  }

 private:
  const PathSpace& space_;
  double theta1_, theta2_;
};

}  // namespace

std::unique_ptr<Mutation> makeLensPerturbation(const PathSpace& space, double r1, double r2) {
  return std::make_unique<LensPerturbation>(space, r1, r2);
}
std::unique_ptr<Mutation> makeCausticPerturbation(const PathSpace& space, double theta1, double theta2) {
  return std::make_unique<CausticPerturbation>(space, theta1, theta2);
}

}  // namespace mlt::veach
