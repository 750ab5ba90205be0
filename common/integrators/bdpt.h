// Bidirectional path tracing as free functions (Veach 1997, ch. 10; the structure of pbrt-v3's bdpt.cpp):
// subpath generation, connection of a light subpath prefix of s vertices with a camera subpath prefix of
// t vertices, and the multiple-importance weight of that strategy. bdpt, lt, pssmlt-bdpt and mmlt all
// call these, so they integrate the same function.
//
// Conventions:
//  - A path of n = s + t vertices has n - 1 segments; maxDepth bounds the segments.
//  - Densities stored on vertices are in AREA measure (pdfFwd: of the vertex as sampled by its own
//    subpath, pdfRev: as it would be sampled from the other side), except next to infinite lights, where
//    pbrt's convention applies: an infinite-light vertex carries a solid-angle density and the vertex
//    after it a planar density (on the disk of radius sceneRadius perpendicular to the direction).
//  - The strategy (s=1, t=1) (a light point connected straight to the camera) is used by lt only; bdpt's
//    weights exclude it (the camera subpath hitting the emitter, s=0 t=2, covers those paths with
//    weight 1). Strategies with t = 0 (a light subpath hitting the lens) are never used.
//  - Russian roulette on subpaths (after rrDepth segments) divides the throughput by the survival
//    probability; the MIS weights ignore it (any weights that sum to one over the strategies that can
//    produce a path give an unbiased sum, and those computed without roulette do).
//
// Streams read (see the dimension map in sampler/sample_source.h):
//   generateCameraSubpath: Camera [0,1] raster, [2,3] lens, bounce i at kCameraDims + i*kBsdfDims.
//   generateLightSubpath:  Light [0] light, [1,2] position, [3,4] direction, bounce i at
//                          kLightDims + i*kBsdfDims.
//   connectBdpt: s=1 -> Connect at connectNeeOffset(t-2) (light choice, point); t=1 -> Camera [2,3].
#pragma once
#include <cstdint>
#include <vector>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/integrators/path_evaluator.h"
#include "common/interfaces/bsdf.h"
#include "common/sampler/sample_source.h"

namespace mlt {

class RenderScene;
class Light;

enum class VertexType : uint8_t { Camera, Light, Surface, InfiniteLight };

struct Vertex {
  VertexType type = VertexType::Surface;
  bool delta = false;       // the direction leaving this vertex along its subpath came from a Dirac lobe
  bool importance = false;  // surface vertex of a light subpath (TransportMode::Importance)
  int lightIndex = -1;      // Light / InfiniteLight vertices, and Surface vertices lying on an area light
  Vec3 p;                   // position (camera: lens point; infinite light: a point 2R away along the direction)
  Vec3 ng, ns;              // normals (zero for the camera and point/spot lights; ns = camera forward axis)
  Vec2 uv;
  Vec3 wo;                  // Surface: unit direction toward the previous vertex of its subpath
  Color beta;               // subpath throughput up to and including this vertex's own sampling weight
  float pdfFwd = 0, pdfRev = 0;
  const Bsdf* bsdf = nullptr;
  const Light* light = nullptr;

  bool isInfiniteLight() const;
  bool isOnSurface() const { return type == VertexType::Surface || (type == VertexType::Light && !isInfiniteLight() && (ng.x != 0 || ng.y != 0 || ng.z != 0)); }
  bool isLight() const { return type == VertexType::Light || type == VertexType::InfiniteLight || (type == VertexType::Surface && light); }
  bool isDeltaLight() const;
  bool isConnectible() const;

  // BSDF value toward `next` (wo = this->wo), with the shading-normal correction (Veach eq. 5.19) for
  // importance transport. Surface vertices only.
  Color f(const Vertex& next) const;
  // Solid-angle density pdfW at this vertex converted to area density at `next` (Veach eq. 8.10).
  float convertDensity(float pdfW, const Vertex& next) const;
  // Area density of sampling `next` from this vertex, which was reached from `prev` (nullptr for endpoints).
  float pdf(const RenderScene& scene, const Vertex* prev, const Vertex& next) const;
  // This vertex is a light: area density (at v) of the light emitting toward v.
  float pdfLight(const RenderScene& scene, const Vertex& v) const;
  // This vertex is a light: density of choosing it as the light subpath's origin (area, or solid angle
  // for infinite lights), given the path continues to v.
  float pdfLightOrigin(const RenderScene& scene, const Vertex& v) const;
  // This vertex is a light: radiance emitted toward v.
  Color Le(const RenderScene& scene, const Vertex& v) const;
};

// Solid-angle density with which the light sampler's infinite lights produce the direction wToLight
// (summed over every infinite light: an escaped camera ray collects all of them).
float infiniteLightDensity(const RenderScene& scene, const Vec3& ref, const Vec3& wToLight);

// Vertex arrays, reused across samples (no allocation per sample once grown).
struct BdptWorkspace {
  std::vector<Vertex> camera, light;
  void reserve(int cameraVertices, int lightVertices);
};

// Upper bound on subpath vertices when maxDepth = -1 (unlimited): roulette ends paths long before; a
// path reaching the cap is truncated (documented bias below rho^kUnlimitedVertices).
constexpr int kUnlimitedVertices = 256;
inline int maxCameraVertices(int maxDepth) { return maxDepth < 0 ? kUnlimitedVertices : maxDepth + 1; }
inline int maxLightVertices(int maxDepth) { return maxDepth < 0 ? kUnlimitedVertices : maxDepth; }

// Camera subpath: path[0] is the camera vertex. pixel: raster = *pixel + Camera[0,1], else Camera[0,1]
// scaled to the film. rrDepth < 0 disables roulette. Returns the vertex count (<= maxVertices).
int generateCameraSubpath(const RenderScene& scene, SampleSource& source, const Vec2* pixel, int maxVertices,
                          int rrDepth, Vertex* path, Vec2* pRaster);
// Light subpath: path[0] is the light vertex. Returns the vertex count (<= maxVertices).
int generateLightSubpath(const RenderScene& scene, SampleSource& source, int maxVertices, int rrDepth, Vertex* path);

// Whether the camera subpath prefix camera[0..t-1] (t >= 2) is a light seen from the lens through Dirac
// scattering only, E S* L, the light's own view (directly, in mirrors, through glass): as the strategy
// s = 0 it is then the only strategy that can make the path (every other one would connect at a Dirac
// vertex), so its MIS weight is 1. veach-mlt leaves these paths to a pass of their own (light_view.h).
inline bool isLightView(const Vertex* camera, int t) {
  if (t < 2 || !camera[t - 1].isLight()) return false;
  for (int i = 1; i <= t - 2; ++i)
    if (!camera[i].delta) return false;
  return true;
}
// Unweighted contribution of strategy (s, t): f(x) / p_{s,t}(x) of the path made of light[0..s-1] and
// camera[t-1..0], visibility included. Resampled endpoints (s=1: a light point from the Connect stream;
// t=1: a lens point from Camera[2,3]) are written to *sampled. t=1 sets *pRaster. Zero if not connectible.
// (s=1, t=1) is evaluated too (lt's view of area lights); bdpt does not call it.
Color connectBdpt(const RenderScene& scene, SampleSource& source, Vertex* light, int s, Vertex* camera, int t,
                  Vertex* sampled, Vec2* pRaster);

// MIS weight of strategy (s,t) for the path connectBdpt just built (Veach eq. 10.9 via the ratio chain of
// pdfFwd / pdfRev; power heuristic with exponent 2). The arrays are modified temporarily and restored.
float misWeight(const RenderScene& scene, Vertex* light, int s, Vertex* camera, int t, const Vertex& sampled,
                MisHeuristic heuristic);

// Fixed-technique entry point for MMLT: builds exactly the light subpath of s vertices and the camera
// subpath of t vertices (no roulette), connects them and returns the unweighted contribution C = f/p and
// the MIS weight. C is zero when either subpath ends early or the connection fails. pRaster is the film
// position (camera raster for t >= 2, the projected position for t = 1).
struct TechniqueSample {
  Color C;
  float weight = 0;
  Vec2 pRaster;
};
// sampledOut (optional): receives the resampled endpoint (s = 1: the light vertex; t = 1: the lens vertex),
// which with ws.camera[0, t) and ws.light[0, s) is the whole path (reversible-jump MLT reads it).
TechniqueSample evaluateTechnique(const RenderScene& scene, SampleSource& source, int s, int t,
                                  MisHeuristic heuristic, BdptWorkspace& ws, const Vec2* pixel = nullptr,
                                  Vertex* sampledOut = nullptr);

// Every technique of path length k (s + t = k + 1, t >= 1) on the same numbers, MIS-weighted and summed:
// sum_s w_{s,t} C_{s,t}, each term what evaluateTechnique(s, t) returns for this source (the subpaths are
// traced once, k + 1 camera and k light vertices, and their prefixes are each technique's subpaths: a
// vertex's numbers do not depend on how long its subpath is). With mmlt's target c_k = n w lum(C) for the
// technique chosen by a coordinate the others do not read, luminance of this is E[c_k | the other
// coordinates]: the same mean b_k, a variance no larger (Rao-Blackwell; tests/bench/b_estimator_bench.cpp).
Color evaluateLength(const RenderScene& scene, SampleSource& source, int k, MisHeuristic heuristic,
                     BdptWorkspace& ws);

}  // namespace mlt
