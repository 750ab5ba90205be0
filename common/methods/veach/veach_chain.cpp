// Veach's chain state, target and start paths (see veach_chain.h).
#include "common/methods/veach/veach_chain.h"

#include <algorithm>
#include <cmath>

#include "common/integrators/bdpt.h"
#include "common/mlt/target.h"
#include "common/render/render_scene.h"

namespace mlt::veach {

VeachChainState::VeachChainState(const PathSpace& space, const MutationSettings& settings, Path start, Pcg32 rng)
    : space_(space), settings_(settings), x_(std::move(start)), rng_(rng) {
  const Camera& cam = space.scene().camera();
  const double r2 = settings.r2 > 0 ? settings.r2 : 0.05 * std::sqrt(double(cam.width()) * double(cam.height()));
  moves_[kBidir] = makeBidirMutation(space);
  moves_[kLens] = makeLensPerturbation(space, settings.r1, std::max(r2, 2 * settings.r1));
  moves_[kCaustic] = makeCausticPerturbation(space, settings.theta1, settings.theta2);
  moves_[kLensSubpath] = makeLensSubpathMutation(space);
  moves_[kMultiChain] = makeMultiChainPerturbation(space, settings.r1, std::max(r2, 2 * settings.r1), settings.theta1,
                                                   settings.theta2);
  moves_[kDeepLens] = makeDeepLensPerturbation(space, settings.r1, std::max(r2, 2 * settings.r1), settings.theta1,
                                               settings.theta2);
  fx_ = space.f(x_, &rasterX_);
}

double VeachChainState::choiceProbability(int kind, const Path& x) const {
  if (!moves_[kind] || !(settings_.weight[kind] > 0) || !moves_[kind]->applicable(x)) return 0;
  double sum = 0;
  for (int t = 0; t < kNumKinds; ++t)
    if (moves_[t] && settings_.weight[t] > 0 && moves_[t]->applicable(x)) sum += settings_.weight[t];
  return settings_.weight[kind] / sum;
}

Proposal VeachChainState::propose() {
  double sum = 0;
  bool applicable[kNumKinds] = {};
  for (int t = 0; t < kNumKinds; ++t) {
    applicable[t] = moves_[t] && settings_.weight[t] > 0 && moves_[t]->applicable(x_);
    if (applicable[t]) sum += settings_.weight[t];
  }
  fy_ = Color();
  if (!(sum > 0)) return {kBidir, 0.0, false};
  double u = rng_.uniformDouble() * sum;
  int kind = -1;
  for (int t = 0; t < kNumKinds; ++t) {
    if (!applicable[t]) continue;
    kind = t;
    if (u < settings_.weight[t]) break;
    u -= settings_.weight[t];
  }
  const double px = settings_.weight[kind] / sum;
  if (!moves_[kind]->propose(x_, rng_, y_)) return {kind, 0.0, false};
  fy_ = space_.f(y_, &rasterY_, &x_);  // x_ has f > 0: its edges are known unoccluded
  if (fy_.isBlack()) return {kind, 0.0, false};
  // The bidirectional mutation with kd = ka = 1 reconnects x to itself: y = x, T-ratio 1.
  if (samePath(x_, y_)) return {kind, 1.0, false};
  const double txy = moves_[kind]->density(x_, y_), tyx = moves_[kind]->density(y_, x_);
  const double py = choiceProbability(kind, y_);
  // T(x -> y) = 0 for a proposal means the rounding of retraced geometry left T's support: reject.
  if (!(txy > 0) || !(tyx > 0) || !(py > 0)) return {kind, 0.0, false};
  return {kind, (py * tyx) / (px * txy), false};
}

void VeachChainState::accept() {
  std::swap(x_, y_);
  fx_ = fy_;
  rasterX_ = rasterY_;
}

void VeachChainTarget::evaluate(PathContribution& out) {
  out.clear();
  const Color f = state_.proposalF();
  if (!f.isBlack()) out.splats.push_back(Splat{state_.proposalRaster(), f, -1, -1});
}

void currentContribution(const VeachChainState& state, PathContribution& out) {
  out.clear();
  if (!state.currentF().isBlack()) out.splats.push_back(Splat{state.currentRaster(), state.currentF(), -1, -1});
}

// ---- start paths --------------------------------------------------------------------------------------

namespace {

PathVertex fromBdpt(const Vertex& b) {
  PathVertex v;
  v.p = b.p;
  v.ng = b.ng;
  v.ns = b.ns;
  v.uv = b.uv;
  v.bsdf = b.bsdf;
  v.light = b.light;
  v.lightIndex = b.lightIndex;
  switch (b.type) {
    case VertexType::Camera: v.kind = VertexKind::Camera; v.ng = v.ns; break;
    case VertexType::Light: v.kind = VertexKind::Light; break;
    default: v.kind = VertexKind::Surface; break;
  }
  return v;
}

}  // namespace

bool samePath(const Path& a, const Path& b) {
  if (a.v.size() != b.v.size()) return false;
  for (size_t i = 0; i < a.v.size(); ++i)
    if (!a.v[i].samePoint(b.v[i])) return false;
  return true;
}

Path bdptStrategyPath(const Vertex* light, int s, const Vertex* camera, int t, const Vertex& sampled, Vec2 uLens) {
  Path x;
  x.uLens = uLens;
  for (int i = 0; i < s; ++i) {
    PathVertex v = fromBdpt(s == 1 ? sampled : light[i]);
    v.specular = i >= 1 && i <= s - 2 && light[i].delta;
    x.v.push_back(v);
  }
  for (int j = t - 1; j >= 0; --j) {
    PathVertex v = fromBdpt(t == 1 ? sampled : camera[j]);
    v.specular = j >= 1 && j <= t - 2 && camera[j].delta;
    if (s == 0 && j == t - 1) {  // the camera subpath's emitter hit is x_0
      v.kind = VertexKind::Light;
      v.specular = false;
      v.ns = v.ng;
    }
    x.v.push_back(v);
  }
  return x;
}

std::optional<StartPath> startPathFromSample(const PathSpace& space, const IntegratorSettings& integrator,
                                             SampleSource& source, double uPick) {
  // The replay of BdptEvaluator::evaluate (evaluators.cpp), keeping the subpaths: same calls, same order,
  // so c(u) is bit-identical to the bootstrap's.
  const RenderScene& scene = space.scene();
  const int maxDepth = integrator.maxDepth;
  BdptWorkspace ws;
  const int maxCamera = maxCameraVertices(maxDepth), maxLight = maxLightVertices(maxDepth);
  ws.reserve(maxCamera, std::max(maxLight, 1));
  Vertex* camera = ws.camera.data();
  Vertex* light = ws.light.data();
  Vec2 cameraRaster;
  const int nCamera = generateCameraSubpath(scene, source, nullptr, maxCamera, integrator.rrDepth, camera, &cameraRaster);
  const int nLight = generateLightSubpath(scene, source, maxLight, integrator.rrDepth, light);
  struct Strategy {
    int s, t;
    double lum;
  };
  std::vector<Strategy> strategies;
  Color total;
  for (int t = 1; t <= nCamera; ++t) {
    for (int s = 0; s <= nLight; ++s) {
      const int segments = s + t - 1;
      if ((s == 1 && t == 1) || segments < 1 || (maxDepth >= 0 && segments > maxDepth)) continue;
      Vertex sampled;
      Vec2 pRaster = cameraRaster;
      const Color C = connectBdpt(scene, source, light, s, camera, t, &sampled, &pRaster);
      // separateDirect: the direct pass's paths are not in the chain's space (EvaluatorPssTarget drops them);
      // nor are the light views of the light-view pass (BdptEvaluator's dropLightViews drops them).
      if (s == 0 && space.withoutLightViews() && isLightView(camera, t)) continue;
      if (C.isBlack() || segments < space.minEdges()) continue;
      const float w = misWeight(scene, light, s, camera, t, sampled, integrator.heuristic);
      const Color L = C * w;
      if (L.isBlack()) continue;
      total += L;
      strategies.push_back({s, t, std::max(0.0, double(luminance(L)))});
    }
  }
  StartPath out;
  out.candidateC = targetFunction(total);
  double sum = 0;
  for (const Strategy& st : strategies) sum += st.lum;
  if (!(sum > 0)) return std::nullopt;
  double u = uPick * sum;
  const Strategy* pick = nullptr;
  for (const Strategy& st : strategies) {
    if (!(st.lum > 0)) continue;
    pick = &st;
    if (u < st.lum) break;
    u -= st.lum;
  }
  Vertex sampled;
  Vec2 pRaster = cameraRaster;
  connectBdpt(scene, source, light, pick->s, camera, pick->t, &sampled, &pRaster);
  source.startStream(Stream::Camera);
  source.seek(2);
  const Vec2 uLens = source.next2D();
  out.path = bdptStrategyPath(light, pick->s, camera, pick->t, sampled, uLens);
  out.s = pick->s;
  out.t = pick->t;
  if (space.f(out.path, nullptr).isBlack()) return std::nullopt;
  return out;
}

}  // namespace mlt::veach
