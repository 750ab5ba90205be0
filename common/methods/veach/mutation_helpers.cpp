// Helpers shared by Veach's mutations (see mutations.h).
#include <cmath>

#include "common/methods/veach/mutations.h"

namespace mlt::veach {

const std::vector<std::string>& mutationKindNames() {
  static const std::vector<std::string> names = {"bidir", "lens", "caustic", "multichain", "lens-subpath"};
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

}  // namespace mlt::veach
