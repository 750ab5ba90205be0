// Each mutation's computed transition density T(x -> y) (common/methods/veach/mutations.h) against the
// move's actual proposals, on the diffuse small Cornell box, and on paths from a point light (the
// bidirectional mutation replacing the vertex next to it, re-adding the light vertex; the caustic
// perturbation turning its emitted direction; the lens subpath mutation connecting to it).
//
// For a fixed x, the moved vertex z of y (the inserted vertex for the bidirectional mutation, the new
// y_{k-1} for the perturbations and the lens subpath mutation) lands in a bin R (a rectangle on a wall)
// with probability
//     P(R) = integral over R of T(x -> y(z)) dA(z),
// counting only proposals with f(y) > 0 (T is the density of proposing y; for paths that carry nothing
// the chain never needs it, and T's split terms assume the connection is unoccluded). P(R) is estimated
// independently by uniform points z in R (area * mean of T(x -> y(z)) [f(y(z)) > 0]); the fraction of
// proposals landing in R must agree within kZ combined standard errors in every bin with enough
// samples. The bidirectional test also shows it can fail: the density of one (l', m') split alone, half
// of Veach's sum over the splits, is rejected.
// Perturbations: the bin holding x's own vertex is not compared. There T ~ 1 / r^2 (a step of length r
// about it) is integrable, but its estimate from uniform points in the bin is too heavy-tailed for a
// standard error; the bins around it test the solid-angle or film-to-area conversion of T.
// Reversibility (for every proposal with f(y) > 0, T(y -> x) > 0): veach_reversibility_test.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "common/methods/veach/mutations.h"
#include "common/methods/veach/path.h"
#include "common/methods/veach/veach_chain.h"
#include "common/render/render_scene.h"
#include "tests/support/test_scenes.h"

namespace mlt {
namespace {

using veach::Path;
using veach::PathSpace;
using veach::PathVertex;

constexpr double kZ = 4.5;  // per bin; ~50 bins per test

// A rectangle origin + a u + b v (a, b in [0, 1)) on a wall, with that wall's vertex data.
struct Bin {
  Vec3 origin, u, v;
  PathVertex proto;
  double area() const { return length(cross(u, v)); }
  bool contains(const Vec3& p) const {
    const Vec3 n = normalize(cross(u, v)), d = p - origin;
    if (std::fabs(dot(d, n)) > 1e-4f) return false;
    const float a = dot(d, u) / dot(u, u), b = dot(d, v) / dot(v, v);
    return a >= 0 && a < 1 && b >= 0 && b < 1;
  }
};

// The wall vertex at p, traced from just inside the wall (the light below the ceiling and the block on
// the floor must not be hit instead).
PathVertex wallVertex(const PathSpace& space, const Vec3& p, const Vec3& normal) {
  const Vec3 inward = dot(normal, Vec3(0, 0, 0) - p) > 0 ? normal : -normal;
  const std::optional<PathVertex> hit = space.trace(p + inward * 0.005f, Vec3(), -inward);
  EXPECT_TRUE(hit.has_value());
  return *hit;
}

// n x n bins on the rectangle (corner, edge u, edge v).
void addGrid(const PathSpace& space, std::vector<Bin>& bins, Vec3 corner, Vec3 u, Vec3 v, int n) {
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      Bin b;
      b.origin = corner + u * (float(i) / n) + v * (float(j) / n);
      b.u = u * (1.0f / n);
      b.v = v * (1.0f / n);
      b.proto = wallVertex(space, b.origin + b.u * 0.5f + b.v * 0.5f, normalize(cross(u, v)));
      bins.push_back(b);
    }
}

// The five walls of the small Cornell box, n x n bins each.
std::vector<Bin> wallBins(const PathSpace& space, int n) {
  std::vector<Bin> bins;
  addGrid(space, bins, {-1, -1, -1}, {2, 0, 0}, {0, 0, 2}, n);  // floor
  addGrid(space, bins, {-1, 1, -1}, {2, 0, 0}, {0, 0, 2}, n);   // ceiling
  addGrid(space, bins, {-1, -1, 1}, {2, 0, 0}, {0, 2, 0}, n);   // back
  addGrid(space, bins, {-1, -1, -1}, {0, 2, 0}, {0, 0, 2}, n);  // left
  addGrid(space, bins, {1, -1, -1}, {0, 2, 0}, {0, 0, 2}, n);   // right
  return bins;
}

// A bin's share of N proposals (count), `got`, against the integral of T over it, `expect`, estimated from
// M uniform points in the bin (area A; sum and sum of squares of T), and z = |got - expect| over their
// combined standard error; nullopt where fewer than 30 proposals are expected and seen (too few to compare).
struct BinComparison {
  double got, expect, z;
};
std::optional<BinComparison> binZ(uint64_t count, uint64_t N, double sum, double sq, int M, double A) {
  const double mean = sum / M;
  const double expect = A * mean, seExpect = A * std::sqrt(std::max(0.0, sq / M - mean * mean) / (M - 1));
  const double got = double(count) / double(N);
  if (std::max(got, expect) * double(N) < 30) return std::nullopt;
  const double seGot = std::sqrt(std::max(got, expect) / double(N));
  return BinComparison{got, expect, std::fabs(got - expect) / std::sqrt(seGot * seGot + seExpect * seExpect)};
}

struct Check {
  double maxZ = 0;
  int binsTested = 0;
  uint64_t inBins = 0;
};

// moved(y): the moved vertex of a proposal of the tested class, or nullopt. place(z): the path y(z).
Check checkDensity(const PathSpace& space, const veach::Mutation& move, const Path& x, const std::vector<Bin>& bins,
                   const std::function<std::optional<Vec3>(const Path&)>& moved,
                   const std::function<Path(const PathVertex&)>& place,
                   const std::function<double(const Path&, const Path&)>& density, uint64_t N, int M,
                   uint64_t seed, int* irreversible = nullptr, const Vec3* singular = nullptr) {
  std::vector<uint64_t> count(bins.size(), 0);
  Pcg32 rng(seed, 1);
  Path y;
  for (uint64_t n = 0; n < N; ++n) {
    if (!move.propose(x, rng, y)) continue;
    if (luminance(space.f(y, nullptr)) <= 0) continue;
    if (irreversible && !veach::samePath(x, y) && !(move.density(y, x) > 0 && move.density(x, y) > 0)) ++*irreversible;
    const std::optional<Vec3> z = moved(y);
    if (!z) continue;
    for (size_t b = 0; b < bins.size(); ++b)
      if (bins[b].contains(*z)) {
        ++count[b];
        break;
      }
  }
  Check c;
  Pcg32 pts(seed, 2);
  for (size_t b = 0; b < bins.size(); ++b) {
    double sum = 0, sq = 0;
    for (int i = 0; i < M; ++i) {
      PathVertex z = bins[b].proto;
      z.p = bins[b].origin + bins[b].u * pts.uniform() + bins[b].v * pts.uniform();
      const Path yz = place(z);
      const double T = luminance(space.f(yz, nullptr)) > 0 ? density(x, yz) : 0.0;
      sum += T;
      sq += T * T;
    }
    c.inBins += count[b];
    const std::optional<BinComparison> cmp = binZ(count[b], N, sum, sq, M, bins[b].area());
    if (!cmp) continue;
    if (singular && bins[b].contains(*singular)) continue;
    ++c.binsTested;
    if (cmp->z > c.maxZ) c.maxZ = cmp->z;
    if (cmp->z > kZ)
      std::printf("  bin %zu: proposals %.5g, integral of T %.5g (z = %.2f)\n", b, cmp->got, cmp->expect, cmp->z);
  }
  return c;
}

// A start path of the given length whose vertex `index` satisfies `want`.
Path findPath(const PathSpace& space, int k, const std::function<bool(const Path&)>& want) {
  IntegratorSettings integrator;
  integrator.maxDepth = 5;
  for (uint64_t i = 0; i < 100000; ++i) {
    IndependentSource src(99, i);
    const auto sp = veach::startPathFromSample(space, integrator, src, 0.5);
    if (sp && sp->path.k() == k && want(sp->path)) return sp->path;
  }
  ADD_FAILURE() << "no start path found";
  return {};
}

bool onPlane(const Vec3& p, int axis, float value) { return std::fabs(p[axis] - value) < 1e-4f; }

TEST(VeachDensity, BidirectionalMutationInsertingOneVertex) {
  const auto scene = RenderScene::build(test::smallCornellBox(16, 16));
  const PathSpace space(*scene, 5);
  const auto move = veach::makeBidirMutation(space);
  // x = L D D E with x_1 on the back wall and x_2 on the floor.
  const Path x = findPath(space, 3, [](const Path& p) { return onPlane(p.v[1].p, 2, 1) && onPlane(p.v[2].p, 1, -1); });
  // Class: (l, m) = (1, 2), ka = 2: one vertex z between x_1 and x_2 (two splits can make it).
  const auto moved = [&](const Path& y) -> std::optional<Vec3> {
    if (y.k() != 4 || !y.v[0].samePoint(x.v[0]) || !y.v[1].samePoint(x.v[1]) || !y.v[3].samePoint(x.v[2]) ||
        !y.v[4].samePoint(x.v[3]))
      return std::nullopt;
    return y.v[2].p;
  };
  const auto place = [&](const PathVertex& z) {
    Path y = x;
    y.v.insert(y.v.begin() + 2, z);
    return y;
  };
  const auto T = [&](const Path& a, const Path& b) { return move->density(a, b); };
  const std::vector<Bin> bins = wallBins(space, 3);
  int irreversible = 0;
  const Check c = checkDensity(space, *move, x, bins, moved, place, T, 1500000, 4000, 5, &irreversible);
  std::printf("bidir: %llu proposals in bins, %d bins tested, max z %.2f, irreversible %d\n",
              (unsigned long long)c.inBins, c.binsTested, c.maxZ, irreversible);
  EXPECT_GE(c.binsTested, 20);
  EXPECT_LT(c.maxZ, kZ);
  EXPECT_EQ(irreversible, 0);
  // Half of Veach's sum (as if only one split could make y) is detected.
  const auto half = [&](const Path& a, const Path& b) { return 0.5 * move->density(a, b); };
  const Check wrong = checkDensity(space, *move, x, bins, moved, place, half, 1500000, 400, 5);
  EXPECT_GT(wrong.maxZ, kZ);
}

// Also on a point light: x = L D E, the fresh y_1 connected to the kept point x_0.
TEST(VeachDensity, LensSubpathMutation) {
  struct Case {
    SceneDesc desc;
    int k;
    bool deltaLight;
  };
  for (const Case& cs : {Case{test::smallCornellBox(16, 16), 3, false}, Case{test::cornellBoxPointSpot(16, 16), 2, true}}) {
    const auto scene = RenderScene::build(cs.desc);
    const PathSpace space(*scene, 5);
    const auto move = veach::makeLensSubpathMutation(space);
    const Path x = findPath(space, cs.k, [&](const Path& p) { return veach::isDeltaPositionLight(p.v[0]) == cs.deltaLight; });
    const auto moved = [&](const Path& y) -> std::optional<Vec3> {
      if (y.k() != x.k()) return std::nullopt;
      return y.v[x.k() - 1].p;
    };
    const auto place = [&](const PathVertex& z) {
      Path y = x;
      y.v[x.k() - 1] = z;
      return y;
    };
    const auto T = [&](const Path& a, const Path& b) { return move->density(a, b); };
    int irreversible = 0;
    const Check c = checkDensity(space, *move, x, wallBins(space, 3), moved, place, T, 300000, 400, 6, &irreversible);
    std::printf("lens subpath%s: %llu in bins, %d bins tested, max z %.2f\n", cs.deltaLight ? " (point light)" : "",
                (unsigned long long)c.inBins, c.binsTested, c.maxZ);
    EXPECT_GE(c.binsTested, 20);
    EXPECT_LT(c.maxZ, kZ);
    EXPECT_EQ(irreversible, 0);
  }
}

// Bins on a square of side 2 * half centred on p (n odd: p inside the middle bin) on the plane axis = p[axis].
std::vector<Bin> binsAround(const PathSpace& space, const Vec3& p, int axis, float half, int n) {
  Vec3 u, v;
  u[(axis + 1) % 3] = 2 * half;
  v[(axis + 2) % 3] = 2 * half;
  std::vector<Bin> bins;
  addGrid(space, bins, p - u * 0.5f - v * 0.5f, u, v, n);
  return bins;
}

TEST(VeachDensity, LensPerturbation) {
  const auto scene = RenderScene::build(test::smallCornellBox(32, 32));
  const PathSpace space(*scene, 5);
  const auto move = veach::makeLensPerturbation(space, 0.1, 3.0);
  // x_{k-1} on the back wall, away from its edges.
  const Path x = findPath(space, 3, [](const Path& p) {
    const Vec3 q = p.v[2].p;
    return onPlane(q, 2, 1) && std::fabs(q.x) < 0.4f && std::fabs(q.y) < 0.4f;
  });
  const int k = x.k();
  const auto moved = [&](const Path& y) -> std::optional<Vec3> { return y.v[k - 1].p; };
  const auto place = [&](const PathVertex& z) {
    Path y = x;
    y.v[k - 1] = z;
    return y;
  };
  const auto T = [&](const Path& a, const Path& b) { return move->density(a, b); };
  int irreversible = 0;
  const Check c = checkDensity(space, *move, x, binsAround(space, x.v[k - 1].p, 2, 0.45f, 7), moved, place, T,
                               300000, 600, 7, &irreversible, &x.v[k - 1].p);
  std::printf("lens perturbation: %llu in bins, %d bins tested, max z %.2f\n", (unsigned long long)c.inBins,
              c.binsTested, c.maxZ);
  EXPECT_GE(c.binsTested, 20);
  EXPECT_LT(c.maxZ, kZ);
  EXPECT_EQ(irreversible, 0);
}

// Also from a point light (the same x on cornellBoxPointSpot's point): the solid angle at the point converts
// to area at y_1 without a cosine at the light.
TEST(VeachDensity, CausticPerturbation) {
  for (const bool pointLight : {false, true}) {
    const auto scene = RenderScene::build(pointLight ? test::cornellBoxPointSpot(32, 32) : test::smallCornellBox(32, 32));
    const PathSpace space(*scene, 5);
    const auto move = veach::makeCausticPerturbation(space, 1e-4, 0.1);
    // x = L D E with x_1 on the floor: the direction leaving the light is perturbed.
    const Path x = findPath(space, 2, [&](const Path& p) {
      const Vec3 q = p.v[1].p;
      if (pointLight && !(veach::isDeltaPositionLight(p.v[0]) && distance(p.v[0].p, Vec3(-0.3f, 0.8f, 0.0f)) < 1e-4f))
        return false;
      return onPlane(q, 1, -1) && q.x < 0 && std::fabs(q.z) < 0.5f;
    });
    const auto moved = [&](const Path& y) -> std::optional<Vec3> { return y.v[1].p; };
    const auto place = [&](const PathVertex& z) {
      Path y = x;
      y.v[1] = z;
      return y;
    };
    const auto T = [&](const Path& a, const Path& b) { return move->density(a, b); };
    int irreversible = 0;
    const Check c = checkDensity(space, *move, x, binsAround(space, x.v[1].p, 1, 0.3f, 7), moved, place, T, 300000,
                                 600, pointLight ? 10 : 8, &irreversible, &x.v[1].p);
    std::printf("caustic perturbation%s: %llu in bins, %d bins tested, max z %.2f\n", pointLight ? " (point light)" : "",
                (unsigned long long)c.inBins, c.binsTested, c.maxZ);
    EXPECT_GE(c.binsTested, 20);
    EXPECT_LT(c.maxZ, kZ);
    EXPECT_EQ(irreversible, 0);
  }
}

// The deep lens perturbation moves two vertices at once (stop n = 2 on x = L D D E: y_2 by the film step,
// y_1 by the turned direction at y_2, connected to the kept light point), so its T is checked jointly:
// the fraction of proposals with (y_2, y_1) in a bin pair R2 x R1 against the integral of T over R2 x R1
// (uniform points in both bins). The smallest steps are raised (0.5 pixel, 0.01 radian) so that T's peak
// where a step is near zero stays within the points' reach; the bin pairs holding that peak (y_2's bin
// around x_2) are not compared. n = 2 is the only stop on such a path (P(n = 2 | x) = 1). T without the
// cosine at the turned direction's vertex is shown to fail.
TEST(VeachDensity, DeepLensPerturbationJointly) {
  const auto scene = RenderScene::build(test::smallCornellBox(32, 32));
  const PathSpace space(*scene, 5);
  const auto move = veach::makeDeepLensPerturbation(space, 0.5, 3.0, 0.01, 0.1);
  // x_2 on the back wall, x_1 on the floor, both away from edges.
  const Path x = findPath(space, 3, [](const Path& p) {
    const Vec3 a = p.v[2].p, b = p.v[1].p;
    return onPlane(a, 2, 1) && std::fabs(a.x) < 0.4f && std::fabs(a.y) < 0.4f && onPlane(b, 1, -1) &&
           std::fabs(b.x) < 0.5f && std::fabs(b.z) < 0.5f;
  });
  const std::vector<Bin> b2 = binsAround(space, x.v[2].p, 2, 0.3f, 5), b1 = binsAround(space, x.v[1].p, 1, 0.3f, 5);
  const auto binOf = [](const std::vector<Bin>& bins, const Vec3& p) {
    for (size_t i = 0; i < bins.size(); ++i)
      if (bins[i].contains(p)) return int(i);
    return -1;
  };
  constexpr uint64_t N = 1000000;
  std::vector<uint64_t> count(b2.size() * b1.size(), 0);
  Pcg32 rng(21, 1);
  Path y;
  int irreversible = 0;
  for (uint64_t n = 0; n < N; ++n) {
    if (!move->propose(x, rng, y) || luminance(space.f(y, nullptr)) <= 0) continue;
    if (!(move->density(x, y) > 0 && move->density(y, x) > 0)) ++irreversible;
    EXPECT_TRUE(y.v[0].samePoint(x.v[0]));  // the light point is kept
    const int i2 = binOf(b2, y.v[2].p), i1 = binOf(b1, y.v[1].p);
    if (i2 >= 0 && i1 >= 0) ++count[size_t(i2) * b1.size() + size_t(i1)];
  }
  EXPECT_EQ(irreversible, 0);
  const auto check = [&](bool withCosine) {
    Pcg32 pts(21, 2);
    constexpr int M = 400;
    double maxZ = 0;
    int tested = 0;
    for (size_t i2 = 0; i2 < b2.size(); ++i2) {
      if (b2[i2].contains(x.v[2].p)) continue;  // the film step's peak
      for (size_t i1 = 0; i1 < b1.size(); ++i1) {
        double sum = 0, sq = 0;
        for (int m = 0; m < M; ++m) {
          Path yz = x;
          yz.v[2] = b2[i2].proto;
          yz.v[2].p = b2[i2].origin + b2[i2].u * pts.uniform() + b2[i2].v * pts.uniform();
          yz.v[1] = b1[i1].proto;
          yz.v[1].p = b1[i1].origin + b1[i1].u * pts.uniform() + b1[i1].v * pts.uniform();
          double T = luminance(space.f(yz, nullptr)) > 0 ? move->density(x, yz) : 0.0;
          if (!withCosine && T > 0) T /= PathSpace::cosAt(yz.v[1], normalize(yz.v[1].p - yz.v[2].p));
          sum += T;
          sq += T * T;
        }
        const std::optional<BinComparison> cmp =
            binZ(count[i2 * b1.size() + i1], N, sum, sq, M, b2[i2].area() * b1[i1].area());
        if (!cmp) continue;
        ++tested;
        maxZ = std::max(maxZ, cmp->z);
      }
    }
    std::printf("deep lens perturbation%s: %d bin pairs tested, max z %.2f\n", withCosine ? "" : " (T without the cosine)",
                tested, maxZ);
    EXPECT_GE(tested, 20);
    return maxZ;
  };
  EXPECT_LT(check(true), kZ);
  EXPECT_GT(check(false), kZ);
}

// ---- a point light as x_0 (path.h, delta-position lights) ----

// x = L D D E on the point light of cornellBoxPointSpot, x_1 on the back wall and x_2 on the floor.
Path pointLightPath(const PathSpace& space) {
  return findPath(space, 3, [](const Path& p) {
    return veach::isDeltaPositionLight(p.v[0]) && distance(p.v[0].p, Vec3(-0.3f, 0.8f, 0.0f)) < 1e-4f &&
           onPlane(p.v[1].p, 2, 1) && onPlane(p.v[2].p, 1, -1);
  });
}

// The bidirectional mutation replacing x_1 next to a point light: y = (x_0, z, x_2, x_3). Three ways make it:
// (l, m) = (0, 2) with z from the light side (the point's emission, pdfDir) or from the eye side (connected
// to the point), and (l, m) = (-1, 2), the light vertex deleted and re-added -- the same point again, with
// probability pmf -- then z from either side as before. T must sum all of them.
TEST(VeachDensity, BidirectionalMutationNextToAPointLight) {
  const auto scene = RenderScene::build(test::cornellBoxPointSpot(16, 16));
  const PathSpace space(*scene, 5);
  const auto move = veach::makeBidirMutation(space);
  const Path x = pointLightPath(space);
  const auto moved = [&](const Path& y) -> std::optional<Vec3> {
    if (y.k() != 3 || !y.v[0].samePoint(x.v[0]) || y.v[1].samePoint(x.v[1]) || !y.v[2].samePoint(x.v[2]) ||
        !y.v[3].samePoint(x.v[3]))
      return std::nullopt;
    return y.v[1].p;
  };
  const auto place = [&](const PathVertex& z) {
    Path y = x;
    y.v[1] = z;
    return y;
  };
  const auto T = [&](const Path& a, const Path& b) { return move->density(a, b); };
  const std::vector<Bin> bins = wallBins(space, 3);
  int irreversible = 0;
  const Check c = checkDensity(space, *move, x, bins, moved, place, T, 1500000, 2000, 9, &irreversible);
  std::printf("bidir next to a point light: %llu proposals in bins, %d bins tested, max z %.2f\n",
              (unsigned long long)c.inBins, c.binsTested, c.maxZ);
  EXPECT_GE(c.binsTested, 20);
  EXPECT_LT(c.maxZ, kZ);
  EXPECT_EQ(irreversible, 0);
}

}  // namespace
}  // namespace mlt
