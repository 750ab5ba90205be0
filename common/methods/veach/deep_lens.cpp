// The deep lens perturbation (this project's, not one of Veach's five): the lens perturbation continued
// through n >= 2 non-specular vertices of the eye subpath, so that the vertices beyond the first one seen
// move too, by small steps, as a primary-sample chain's small step moves all of them.
//
// Why: Veach's perturbations move only the first non-specular vertex seen from the lens (lens), the last
// one before the lens (caustic), or the chain of vertices up to the first connectible pair (multi-chain);
// every vertex further toward the light is moved only by the bidirectional and lens subpath mutations,
// which regenerate it from scratch and are seldom accepted where the light arrives indirectly (caustic-
// mirror's dark room: docs/VEACH.md, "Steps, weights and whole-path regeneration"). This move perturbs
// them all a little.
//
// x = (x_0 light, ..., x_k lens). d_1 > d_2 > ... > d_M are x's non-specular vertices seen from the lens
// (d_1 = eyeChainEnd(x)). A stop n >= 2 is allowed if x_{d_n - 1} is non-specular: y_{d_n} is then
// connected to the kept x_{d_n - 1} (possibly the light point). Stopping on the light itself (the last chain
// hitting it again, as the multi-chain perturbation may) was tried and left out: on glossy-plates' small
// lights most such proposals miss, and without it the move did better on every scene measured (docs/
// VEACH.md). n is drawn with P(n | x) = 2^-(n-2) / (sum over allowed n' of 2^-(n'-2)), favouring short
// moves (they are accepted more often); the allowed stops depend only on x's vertex types, which y keeps.
// Then, as the multi-chain perturbation (multichain.cpp): the film position moves by an exponential step
// in [r1, r2] pixels and the first chain E S* D is retraced with x's lobes to y_{d_1}; at each d_c, c < n,
// x's direction toward x_{d_c - 1} is turned by an exponential angle theta_c in [theta1, theta2] about a
// uniform axis and the next chain (possibly empty: a diffuse x_{d_c - 1}) is retraced from y_{d_c} with
// x's lobes to y_{d_{c+1}}. Every chain is traced from the eye, so (canonical measure, path.h)
//     T(x -> y) = P(n | x) p_film(|d|) W H pdfDir(y) |cos y_{k-1}| / |y_k - y_{k-1}|^2
//                 * prod over c < n of  p_w(theta_c) |cos y_{d_c - 1}| / |y_{d_c} - y_{d_c - 1}|^2,
// p_film(r) = p_R(r) / (2 pi r), p_w(theta) = p_theta(theta) / (2 pi sin theta): both steps are symmetric
// in x and y (theta_c is the angle between x's and y's directions at d_c), as in the lens and multi-chain
// perturbations. n is read back from (x, y): y keeps x_0 .. x_{d_n - 1} and moves every d_c, c <= n.
#include <cmath>

#include "common/methods/veach/mutations.h"
#include "common/render/render_scene.h"

namespace mlt::veach {

namespace {

// d_1 > ... > d_M into d (storage reused): x's non-specular vertices between the light and the lens.
void diffuseVertices(const Path& x, std::vector<int>& d) {
  d.clear();
  for (int i = x.k() - 1; i >= 1; --i)
    if (!x.v[i].specular) d.push_back(i);
}

// Whether the move may stop at d_n (n >= 2, 1-based): y_{d_n} connects to the kept x_{d_n - 1}.
bool allowedStop(const Path& x, const std::vector<int>& d, size_t n) {
  return n >= 2 && n <= d.size() && !x.v[d[n - 1] - 1].specular;
}

// P(n | x) up to the normalization: 2^-(n-2).
double stopWeight(size_t n) { return std::ldexp(1.0, -int(n - 2)); }

double stopWeightSum(const Path& x, const std::vector<int>& d) {
  double sum = 0;
  for (size_t n = 2; n <= d.size(); ++n)
    if (allowedStop(x, d, n)) sum += stopWeight(n);
  return sum;
}

class DeepLensPerturbation final : public Mutation {
 public:
  DeepLensPerturbation(const PathSpace& space, double r1, double r2, double theta1, double theta2)
      : space_(space), r1_(r1), r2_(r2), theta1_(theta1), theta2_(theta2) {}

  bool applicable(const Path& x) const override {
    thread_local std::vector<int> d;
    if (x.k() < 2) return false;
    diffuseVertices(x, d);
    return stopWeightSum(x, d) > 0;
  }

  bool propose(const Path& x, Pcg32& rng, Path& y) const override {
    thread_local std::vector<int> d;
    diffuseVertices(x, d);
    const double sum = stopWeightSum(x, d);
    if (!(sum > 0)) return false;
    double u = rng.uniformDouble() * sum;
    size_t n = 0;
    for (size_t m = 2; m <= d.size(); ++m) {
      if (!allowedStop(x, d, m)) continue;
      n = m;
      if (u < stopWeight(m)) break;
      u -= stopWeight(m);
    }
    return perturbEyeChains(space_, x, rng, r1_, r2_, theta1_, theta2_, d, n, y);
  }

  double density(const Path& x, const Path& y) const override {
    thread_local std::vector<int> d, dOfY;
    const int k = x.k();
    if (k < 2 || y.k() != k || !x.v[k].samePoint(y.v[k])) return 0;
    diffuseVertices(x, d);
    diffuseVertices(y, dOfY);
    if (d != dOfY) return 0;
    int j = 0;  // the first vertex from the light that moved: d_n
    while (j < k && x.v[j].samePoint(y.v[j])) ++j;
    size_t n = 0;
    for (size_t m = 1; m <= d.size(); ++m)
      if (d[m - 1] == j) n = m;
    if (!allowedStop(x, d, n)) return 0;
    for (int i = j + 1; i < k; ++i)  // the retraced specular vertices kept their lobes
      if (x.v[i].specular && transmits(x, i) != transmits(y, i)) return 0;
    return stopWeight(n) / stopWeightSum(x, d) * eyeChainsDensity(space_, x, y, r1_, r2_, theta1_, theta2_, d, n);
  }

 private:
  const PathSpace& space_;
  double r1_, r2_, theta1_, theta2_;
};

}  // namespace

std::unique_ptr<Mutation> makeDeepLensPerturbation(const PathSpace& space, double r1, double r2, double theta1,
                                                   double theta2) {
  return std::make_unique<DeepLensPerturbation>(space, r1, r2, theta1, theta2);
}

}  // namespace mlt::veach
