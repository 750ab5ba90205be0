// Veach's multi-chain perturbation (Veach 1997, sec. 11.4.3.3): the lens perturbation continued through
// paths E S+ D S+ D ... whose first diffuse vertex cannot be connected (its light-side neighbour is
// specular). The film position moves as in the lens perturbation and the first chain is retraced with the
// same lobes to the diffuse vertex d_1. At each diffuse vertex d_i whose light-side neighbour is specular,
// the direction toward the next chain is x's direction at d_i turned by an angle theta (exponential in
// [theta1, theta2], as the caustic perturbation) about a uniform axis, and the next chain is retraced with
// x's lobes to d_{i+1}. The last diffuse vertex d_n is connected to the kept x_{d_n - 1} (non-specular), or
// the last chain ends on the light (S* L: it must hit an emitter).
//
// All chains are traced from the eye side, so the density is in the canonical measure directly:
//     T(x -> y) = p_film(|d|) W H pdfDir(y) |cos y_{k-1}| / |y_k - y_{k-1}|^2
//                 * prod over i < n of  p_w(theta_i) |cos y_{d_i - 1}| / |y_{d_i} - y_{d_i - 1}|^2,
// p_w(theta) = p_theta(theta) / (2 pi sin theta), theta_i the angle between x's and y's directions at
// d_i (symmetric, as the film step).
#include <algorithm>
#include <cmath>

#include "common/methods/veach/mutations.h"
#include "common/render/render_scene.h"

namespace mlt::veach {

namespace {

// The diffuse vertices d_1 > d_2 > ... > d_n of x's eye side, E S+ D (S+ D)* followed by a connectible
// vertex or the light, into d (its storage reused: no allocation per proposal once grown); empty if x does
// not have that form with n >= 2. Returns whether d is not empty.
bool chainEnds(const Path& x, std::vector<int>& d) {
  d.clear();
  const int k = x.k();
  int i = k - 1;
  if (i < 1 || !x.v[i].specular) return false;  // the first chain has a specular vertex
  for (;;) {
    while (i >= 1 && x.v[i].specular) --i;
    if (i < 0) break;
    d.push_back(i);
    if (i == 0) {                       // the last chain ends on the light, which it must hit again:
      if (isDeltaPositionLight(x.v[0])) d.clear();  // never a point or spot light
      break;
    }
    if (!x.v[i - 1].specular) break;    // a connectible pair: done
    --i;
  }
  if (i < 0 || d.size() < 2) d.clear();
  return !d.empty();
}

class MultiChainPerturbation final : public Mutation {
 public:
  MultiChainPerturbation(const PathSpace& space, double r1, double r2, double theta1, double theta2)
      : space_(space), r1_(r1), r2_(r2), theta1_(theta1), theta2_(theta2) {}

  bool applicable(const Path& x) const override {
    thread_local std::vector<int> d;
    return chainEnds(x, d);
  }

  bool propose(const Path& x, Pcg32& rng, Path& y) const override {
    thread_local std::vector<int> d;
    chainEnds(x, d);
    return perturbEyeChains(space_, x, rng, r1_, r2_, theta1_, theta2_, d, d.size(), y);
  }

  double density(const Path& x, const Path& y) const override {
    thread_local std::vector<int> d, dOfY;
    const int k = x.k();
    if (!chainEnds(x, d) || y.k() != k || !chainEnds(y, dOfY) || dOfY != d || !x.v[k].samePoint(y.v[k])) return 0;
    for (int i = 0; i < d.back(); ++i)
      if (!x.v[i].samePoint(y.v[i])) return 0;
    for (int i = d.back() + 1; i < k; ++i) {
      const bool diffuse = std::find(d.begin(), d.end(), i) != d.end();
      if (!diffuse && transmits(x, i) != transmits(y, i)) return 0;
    }
    return eyeChainsDensity(space_, x, y, r1_, r2_, theta1_, theta2_, d, d.size());
  }

 private:
  const PathSpace& space_;
  double r1_, r2_, theta1_, theta2_;
};

}  // namespace

std::unique_ptr<Mutation> makeMultiChainPerturbation(const PathSpace& space, double r1, double r2, double theta1,
                                                     double theta2) {
  return std::make_unique<MultiChainPerturbation>(space, r1, r2, theta1, theta2);
}

}  // namespace mlt::veach
