// Helpers shared by Veach's mutations (see mutations.h).
#include <cmath>

#include "common/methods/veach/mutations.h"
#include "common/render/render_scene.h"

namespace mlt::veach {

const std::vector<std::string>& mutationKindNames() {
  static const std::vector<std::string> names = {"bidir", "lens", "caustic", "multichain", "lens-subpath", "deep-lens"};
  return names;
}

int eyeChainEnd(const Path& x) {
  const int k = x.k();
  for (int i = k - 1; i >= 1; --i)
    if (!x.v[i].specular) return i;
  return -1;
}

std::optional<BsdfSample> sampleDirection(const PathVertex& from, const PathVertex& prev, TransportMode mode,
                                          Pcg32& rng, Vec3* wiWorld) {
  const Frame frame(from.ns);
  const Vec3 wo = normalize(prev.p - from.p);
  const float uc = rng.uniform();
  const Vec2 ud = rng.uniform2();
  std::optional<BsdfSample> bs = from.bsdf->sample(frame.toLocal(wo), uc, ud, BsdfQuery{from.uv, mode});
  if (!bs || bs->f.isBlack() || !(bs->pdfW > 0)) return std::nullopt;
  *wiWorld = normalize(frame.toWorld(bs->wi));
  return bs;
}

std::optional<Vec3> followLobe(const PathVertex& s, const PathVertex& prev, bool transmit, TransportMode mode) {
  static constexpr float kU[] = {0.0f, kOneMinusEpsilon, 0.5f, 0.25f, 0.75f, 0.05f, 0.95f};
  const Frame frame(s.ns);
  const Vec3 wo = frame.toLocal(normalize(prev.p - s.p));
  for (float u : kU) {
    const std::optional<BsdfSample> bs = s.bsdf->sample(wo, u, Vec2(0.5f, 0.5f), BsdfQuery{s.uv, mode});
    if (!bs || !bs->delta || !(bs->pdfW > 0) || bs->f.isBlack()) continue;
    if ((wo.z * bs->wi.z < 0) == transmit) return normalize(frame.toWorld(bs->wi));
  }
  return std::nullopt;
}

bool transmits(const Path& x, int i) {
  const PathVertex& s = x.v[i];
  return dot(x.v[i + 1].p - s.p, s.ns) * dot(x.v[i - 1].p - s.p, s.ns) < 0;  // as followLobe: shading frame
}

double exponentialStepDensity(double s, double s1, double s2) {
  if (!(s > 0)) return 0;
  // The step is measured back from float geometry (~1e-7 absolute in angle, ~1e-3 relative at theta1 =
  // 1e-4): the support gets 1% slack, the same for T(x -> y) and T(y -> x) (the step is symmetric).
  if (s < s1 * (1 - 1e-2) || s > s2 * (1 + 1e-2)) return 0;
  return 1 / (s * std::log(s2 / s1));
}

double sampleExponentialStep(Pcg32& rng, double s1, double s2) {
  return s2 * std::exp(-std::log(s2 / s1) * rng.uniformDouble());
}

std::optional<Vec2> perturbRaster(const PathSpace& space, const Path& x, Pcg32& rng, double r1, double r2) {
  Vec2 r0;
  if (!space.raster(x, &r0)) return std::nullopt;
  const double R = sampleExponentialStep(rng, r1, r2);
  const double phi = 2 * M_PI * rng.uniformDouble();
  const Vec2 raster(float(r0.x + R * std::cos(phi)), float(r0.y + R * std::sin(phi)));
  const Camera& cam = space.scene().camera();
  if (!(raster.x >= 0 && raster.x < float(cam.width()) && raster.y >= 0 && raster.y < float(cam.height())))
    return std::nullopt;
  return raster;
}

Vec3 perturbDirection(const Path& x, int at, int toward, Pcg32& rng, double theta1, double theta2) {
  const Vec3 w = normalize(x.v[toward].p - x.v[at].p);
  const double theta = sampleExponentialStep(rng, theta1, theta2);
  const double phi = 2 * M_PI * rng.uniformDouble(), st = std::sin(theta);
  return normalize(Frame(w).toWorld(Vec3(float(st * std::cos(phi)), float(st * std::sin(phi)), float(std::cos(theta)))));
}

bool retraceSpecularChain(const PathSpace& space, const Path& x, Path& y, int first, int last, int step, Vec3 dir,
                          TransportMode mode) {
  if ((last - first) * step < 0) return false;
  for (int i = first;; i += step) {
    const PathVertex& prev = y.v[i - step];
    std::optional<PathVertex> hit = space.trace(prev.p, prev.kind == VertexKind::Camera ? Vec3() : prev.ng, dir);
    if (!hit) return false;
    if (i != last) {
      const std::optional<Vec3> next = followLobe(*hit, prev, transmits(x, i), mode);
      if (!next) return false;
      hit->specular = true;
      dir = *next;
    } else if (i == 0) {
      if (!space.makeLightVertex(*hit)) return false;
    } else {
      if (hit->bsdf->isDelta()) return false;
      hit->specular = false;
    }
    y.v[i] = *hit;
    if (i == last) return true;
  }
}

double filmStepDensity(const PathSpace& space, const Path& x, const Path& y, double r1, double r2) {
  Vec2 rx, ry;
  if (!space.raster(x, &rx) || !space.raster(y, &ry)) return 0;
  const double dx = double(ry.x) - rx.x, dy = double(ry.y) - rx.y, d = std::sqrt(dx * dx + dy * dy);
  const double pFilm = exponentialStepDensity(d, r1, r2) / (2 * M_PI * d);
  const Camera& cam = space.scene().camera();
  return pFilm * double(cam.width()) * double(cam.height()) * space.eyeStep(y, y.k() - 1);
}

bool perturbEyeChains(const PathSpace& space, const Path& x, Pcg32& rng, double r1, double r2, double theta1,
                      double theta2, const std::vector<int>& ends, size_t n, Path& y) {
  const int k = x.k();
  const std::optional<Vec2> raster = perturbRaster(space, x, rng, r1, r2);
  if (!raster) return false;
  y = x;
  Vec3 dir;
  y.v[k] = space.cameraVertex(*raster, x.uLens, &dir);
  int first = k - 1;
  for (size_t c = 0; c < n; ++c) {
    if (c > 0) {
      // Turn x's direction at ends[c-1] (toward the light) by theta about a uniform axis.
      const int e = ends[c - 1];
      dir = perturbDirection(x, e, e - 1, rng, theta1, theta2);
      first = e - 1;
    }
    if (!retraceSpecularChain(space, x, y, first, ends[c], -1, dir, TransportMode::Radiance)) return false;
  }
  return true;
}

double eyeChainsDensity(const PathSpace& space, const Path& x, const Path& y, double r1, double r2, double theta1,
                        double theta2, const std::vector<int>& ends, size_t n) {
  double T = filmStepDensity(space, x, y, r1, r2);
  for (size_t c = 0; c + 1 < n && T > 0; ++c) {
    const int e = ends[c];
    const Vec3 wx = normalize(x.v[e - 1].p - x.v[e].p), wy = normalize(y.v[e - 1].p - y.v[e].p);
    const double theta = std::atan2(double(length(cross(wx, wy))), double(dot(wx, wy)));
    const double pW = exponentialStepDensity(theta, theta1, theta2) / (2 * M_PI * std::sin(theta));
    const float d2 = distanceSquared(y.v[e].p, y.v[e - 1].p);
    T *= pW * PathSpace::cosAt(y.v[e - 1], wy) / d2;
  }
  return T;
}

}  // namespace mlt::veach
