// Path inversion for a technique change (Bitterli et al. 2017, "Reversible Jump Metropolis Light Transport
// using Inverse Mappings", sec. 4-6): an MMLT path of k segments sampled by bdpt technique (s, t) is
// turned back into the primary samples with which technique (s', t') produces the same path.
//
// The path is the vertex list z[0..k] from the camera (z[0], the lens point) to the light (z[k]). Under
// technique (s, t) the camera subpath is z[0..t-1] and the light subpath z[k], z[k-1], ..., z[t].
// Inverting technique (s, t) ("an inverse random walk", eq. 39) writes, in the fixed blocks of the
// dimension map (common/sampler/sample_source.h):
//   Connect[kConnectTechniqueDim]  MMLT's technique choice: the interval [s/n, (s+1)/n) at gamma (eq. 40)
//   Camera[0..3]                   t >= 2: raster position and lens (Camera::invertGenerateRay);
//                                  t = 1: the lens sample of the t = 1 connection (invertSampleWi)
//   Camera bounce blocks           the BSDF sample at z[1..t-2] toward the next camera vertex
//   Light[0..4]                    s >= 2: light choice (LightSampler::invertSample) and sampleLe
//   Light bounce blocks            the BSDF sample at z[k-1..t+1] (importance) toward the next light vertex
//   Connect NEE block of t - 2     s = 1: light choice and sampleLi from z[k-1]
// Every other coordinate of the footprint of length k (the coordinates any technique of that length
// reads) is resampled uniformly (sec. 6.1: unused dimensions carry no information and have Jacobian 1).
// Lobe choices are probabilistic inverses (eq. 41-44, inside Bsdf::invertSample).
//
// The Jacobian |J[S^-1_(s,t)](z)| of eq. 38 is the product of the per-routine Jacobians (the formula
// after eq. 39), each converted to the path's measure: area at surface vertices and at finite lights
// (solid-angle densities times |cos| / d^2 at the vertex they produce, Veach eq. 8.10), solid angle for
// a vertex at infinity, and the planar disk density times |cos| for the vertex after an infinite light
// (the conventions of bdpt.h). A Dirac lobe's discrete probability is converted like a density: its
// delta function is the same in every technique that samples that vertex and cancels in eq. 38. Then
// C_(s,t) * J_(s,t) = f(path) for every technique (tested), and eq. 38 reduces to eq. 33: w' / w.
//
// Inversion fails (nullopt: the move is rejected, never the job) where the technique cannot produce the
// path: a delta light reached by the camera walk (s = 0), a vertex at infinity with several infinite
// lights (which light is ambiguous, and f differs between them), a routine whose inverse rejects.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "common/core/rng.h"
#include "common/integrators/bdpt.h"
#include "common/integrators/path_evaluator.h"
#include "common/sampler/sample_source.h"

namespace mlt {

class RenderScene;

// One path of an MMLT state: its vertices from the camera to the light and what technique (s, t) made of it.
struct MmltPath {
  int s = 0, t = 0;
  std::vector<Vertex> z;  // z[0] camera ... z[k] light; k = z.size() - 1
  Color C;                // unweighted contribution f / p_(s,t)
  float weight = 0;       // MIS weight w_(s,t)
  Vec2 pRaster;
  int length() const { return static_cast<int>(z.size()) - 1; }
};

// Runs technique (s, t) on `source` exactly as MMLT's target does (evaluateTechnique) and collects the
// path. False if the technique produces no contribution.
bool traceTechnique(const RenderScene& scene, SampleSource& source, int s, int t, MisHeuristic heuristic,
                    BdptWorkspace& ws, MmltPath* out);

// Appends the splat MMLT's target makes of p (methods/mmlt/mmlt_method.h: C w(s,t) n, n = the number of
// techniques of p's length, so that the uniform technique choice sums to bdpt); nothing if C w n is not > 0.
void appendMmltSplat(const MmltPath& p, PathContribution& out);

// The technique index s that MMLT's target reads for length k (the Connect stream's first coordinate).
int mmltTechniqueOf(SampleSource& source, int k);

struct PrimaryWrite {
  int stream, index;
  float value;
};
struct PathInverse {
  std::vector<PrimaryWrite> writes;  // every coordinate of the footprint of length k
  double jacobian = 0;               // |J[S^-1_(s,t)](z)|, = p_(s,t)(z) in the path's measure
};

// Coordinates of each stream that some technique of length k reads: [0, footprint(k, stream)).
int mmltFootprint(int k, Stream stream);

// Inverts technique (s, t), s + t = k + 1, for the path z. rng supplies gamma (eq. 40-44).
std::optional<PathInverse> invertTechnique(const RenderScene& scene, const std::vector<Vertex>& z, int s, int t,
                                           Pcg32& rng);

// True if technique (s, t) connects the path at a Dirac vertex (its contribution is zero by construction).
bool connectsAtDelta(const std::vector<Vertex>& z, int s, int t);

// True if two paths have the same vertices (positions to `tolerance` relative to the scene radius;
// vertices at infinity by direction).
bool samePath(const RenderScene& scene, const std::vector<Vertex>& a, const std::vector<Vertex>& b,
              float tolerance = 1e-3f);

}  // namespace mlt
