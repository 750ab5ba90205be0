// Veach's mutations (Veach 1997, sec. 11.4; Veach and Guibas 1997, sec. 5), each with its exact
// transition density T(x -> y) in the canonical measure of path.h, so that the chain's acceptance
//     a(x -> y) = min(1, f(y) T(y -> x) / (f(x) T(x -> y)))                        (Veach eq. 11.3)
// is computed, never assumed symmetric. Paths are x = (x_0 light, ..., x_k lens).
//
//  bidir         delete x_{l+1} .. x_{m-1} (kd = m - l edges, l in [-1, k-1], m in [1, k+1]); kd by pd1,
//                l uniform; add ka edges (pa1 around kd) as l' vertices from the light side and m' from the
//                eye side, then connect (sec. 11.4.2). T sums over every (l, m, l') that yields y.
//  lens          perturb the film position by an exponential step in [r1, r2] pixels, retrace the eye chain
//                E S* D with the same lobes, connect to the kept x_{m-1} (ES*D(D|L), sec. 11.4.3.1).
//  caustic       perturb the direction leaving x_j by an exponential angle in [theta1, theta2], retrace
//                S* toward the eye, connect to the kept lens point ((D|L) S* D E, sec. 11.4.3.2).
//  multichain    lens perturbation continued through E S+ D (S+ D)* (D|L): at each diffuse vertex whose
//                light-side neighbour is specular, x's outgoing direction turned by an exponential angle
//                in [theta1, theta2], the next chain retraced with x's lobes (sec. 11.4.3.3).
//  lens-subpath  replace the eye subpath E S* D by a fresh one through a uniform film position (sec. 11.4.4).
//  deep-lens     (this project's) the multi-chain perturbation continued through diffuse vertices: the
//                film position and the directions at the first n >= 2 non-specular vertices seen from the
//                lens turned by small steps, the vertices between retraced (deep_lens.cpp).
//
// Specular chains traced from the eye are in the canonical measure of path.h; those traced from the light
// (bidir's light side, the caustic perturbation) are converted (path.h lightChainToCanonical).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "common/core/rng.h"
#include "common/methods/veach/path.h"

namespace mlt::veach {

// Mutation kinds: index = Proposal::kind; names as reported in statistics and metadata.
enum MutationKind : int {
  kBidir = 0,
  kLens = 1,
  kCaustic = 2,
  kMultiChain = 3,
  kLensSubpath = 4,
  kDeepLens = 5,
  kNumKinds = 6
};
const std::vector<std::string>& mutationKindNames();

struct MutationSettings {
  // Selection weights; a move inapplicable to the current path is skipped (its weight removed), and the
  // probability of the chosen move enters T (veach_chain.h). Lens and caustic perturbations at 2: better in
  // every one of 8 seeds on the Cornell box and door-ajar (6-9%), unresolved elsewhere (docs/VEACH.md,
  // "Move weights on the Cornell box").
  double weight[kNumKinds] = {1.0, 2.0, 2.0, 1.0, 1.0, 0.0};
  double r1 = 0.1;          // lens perturbation: step in pixels, exponential in [r1, r2]
  double r2 = 0;            // 0: 5% of sqrt(film pixels)
  double theta1 = 1e-4;     // caustic perturbation: angle in radians, exponential in [theta1, theta2]
  double theta2 = 0.1;
  // Not a mutation: the light-view pass (light_view.h), in samples per pixel per mutation per pixel
  // (0: off, the chains carry the paths E S* L).
  double lightView = 0.25;
};

class Mutation {
 public:
  virtual ~Mutation() = default;
  virtual bool applicable(const Path& x) const = 0;
  // Proposes y from x; false when the move cannot produce a path (the chain then rejects).
  virtual bool propose(const Path& x, Pcg32& rng, Path& y) const = 0;
  // T(x -> y) given that this move was chosen; 0 when it cannot produce y from x.
  virtual double density(const Path& x, const Path& y) const = 0;
};

std::unique_ptr<Mutation> makeBidirMutation(const PathSpace& space);
std::unique_ptr<Mutation> makeLensPerturbation(const PathSpace& space, double r1, double r2);
std::unique_ptr<Mutation> makeCausticPerturbation(const PathSpace& space, double theta1, double theta2);
std::unique_ptr<Mutation> makeLensSubpathMutation(const PathSpace& space);
std::unique_ptr<Mutation> makeMultiChainPerturbation(const PathSpace& space, double r1, double r2, double theta1,
                                                     double theta2);
std::unique_ptr<Mutation> makeDeepLensPerturbation(const PathSpace& space, double r1, double r2, double theta1,
                                                   double theta2);

// ---- shared helpers -----------------------------------------------------------------------------------
// The eye chain E S* D: the index m of the first non-specular vertex seen from the lens (x_{k-1}, x_{k-2},
// ...), or -1 if it is the light (E S* L) or the path is too short.
int eyeChainEnd(const Path& x);
// Samples a direction from vertex `from` reached from `prev` (BSDF sampling in `mode`); nullopt if absorbed.
std::optional<BsdfSample> sampleDirection(const PathVertex& from, const PathVertex& prev, TransportMode mode,
                                          Pcg32& rng, Vec3* wiWorld);
// Follows the lobe of type `transmit` at specular vertex `s` reached from `prev`: the outgoing world
// direction, or nullopt if the BSDF has no such lobe there (total internal reflection, a type change).
std::optional<Vec3> followLobe(const PathVertex& s, const PathVertex& prev, bool transmit, TransportMode mode);
// Whether x's specular vertex i reflects or transmits.
bool transmits(const Path& x, int i);
// Exponential step density of Veach's perturbations: s = s2 exp(-ln(s2/s1) u), density 1 / (s ln(s2/s1)).
double exponentialStepDensity(double s, double s1, double s2);
// Draws that step (one uniform from rng).
double sampleExponentialStep(Pcg32& rng, double s1, double s2);
// The film position of x moved by R (cos phi, sin phi), R an exponential step in [r1, r2], phi uniform
// (two uniforms); nullopt if x has no film position or the new one leaves the film.
std::optional<Vec2> perturbRaster(const PathSpace& space, const Path& x, Pcg32& rng, double r1, double r2);
// x's direction from vertex `at` toward `toward`, turned by theta (an exponential step in [theta1,
// theta2]) about a uniform axis (two uniforms).
Vec3 perturbDirection(const Path& x, int at, int toward, Pcg32& rng, double theta1, double theta2);
// The lens, multi-chain and deep lens perturbations' film step as a density of y's first vertex in the
// canonical measure: p_R(|d|) / (2 pi |d|) * W H * pdfDir(y) |cos y_{k-1}| / |y_k - y_{k-1}|^2 (|d| the
// distance between x's and y's film positions; perturbations.cpp); 0 if either has none.
double filmStepDensity(const PathSpace& space, const Path& x, const Path& y, double r1, double r2);
// The eye-side chains of the multi-chain and deep lens perturbations: y = x with its film position moved
// (perturbRaster) and the chains ending at x's non-specular vertices ends[0] > ends[1] > ... > ends[n-1]
// retraced from the eye with x's lobes, the direction at each ends[c], c < n - 1, toward the next chain
// x's turned by an exponential angle in [theta1, theta2] (perturbDirection). False if a chain fails.
bool perturbEyeChains(const PathSpace& space, const Path& x, Pcg32& rng, double r1, double r2, double theta1,
                      double theta2, const std::vector<int>& ends, size_t n, Path& y);
// Its density: filmStepDensity times, per turned direction, p_w(theta) |cos y_{e-1}| / |y_e - y_{e-1}|^2
// (e = ends[c], c < n - 1, theta the angle between x's and y's directions there, p_w(theta) =
// p_theta(theta) / (2 pi sin theta)).
double eyeChainsDensity(const PathSpace& space, const Path& x, const Path& y, double r1, double r2, double theta1,
                        double theta2, const std::vector<int>& ends, size_t n);
// Retraces y's vertices first, first + step, ..., last (step = +1 toward the eye, -1 toward the light)
// from y.v[first - step] in direction dir: the vertices before `last` follow x's lobes (followLobe in `mode`) and are specular;
// `last` must be a non-Dirac surface (or, as vertex 0, a light). False if a ray escapes or a lobe or the
// end condition fails.
bool retraceSpecularChain(const PathSpace& space, const Path& x, Path& y, int first, int last, int step, Vec3 dir,
                          TransportMode mode);

}  // namespace mlt::veach
