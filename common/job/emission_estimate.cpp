#include "common/job/emission_estimate.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/core/rng.h"
#include "common/integrators/evaluators.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"

namespace mlt {

namespace {

constexpr float kBelowOne = 0x1.fffffep-1f;  // the largest float < 1
constexpr uint64_t kPilotKey = 0x656d6970ULL, kStageKey = 0x656d6973ULL;  // "emip", "emis"

// One camera ray through pixel (x, y) at the position u in the pixel: the luminance of Le seen.
double emissionSeen(const PathEvaluator& pt, IndependentSource& source, PathContribution& path, int x, int y, Vec2 u) {
  source.setPixelPoint(u);
  path.clear();
  const Vec2 pixel{float(x), float(y)};
  pt.evaluate(source, &pixel, path);
  const double v = luminance(path.total());
  if (!(std::isfinite(v) && v >= 0))
    throw std::runtime_error("emission estimate: the ray through pixel (" + std::to_string(x) + ", " +
                             std::to_string(y) + ") sees invalid emission " + std::to_string(v));
  return v;
}

template <typename Body>
void forRows(int height, bool parallel, const Body& body) {
  const auto rows = [&](const tbb::blocked_range<int>& r) {
    for (int y = r.begin(); y != r.end(); ++y) body(y);
  };
  if (parallel) tbb::parallel_for(tbb::blocked_range<int>(0, height, 4), rows);
  else rows(tbb::blocked_range<int>(0, height));
}

}  // namespace

int emissionCellsPerPixelAxis(int width, int height) {
  const double P = double(width) * double(height);
  return int(std::max(1.0, std::ceil(std::sqrt(double(kEmissionMinCells) / P))));
}

namespace {
bool seenOnFilm(const Light& light) {  // area lights; the others are never seen on the film
  return !(light.deltaPosition() || light.infinite() || light.power().isBlack());
}
}  // namespace

int footprintPointsPerSide(const RenderScene& scene) {
  uint64_t areaLights = 0;
  for (const std::unique_ptr<Light>& light : scene.lights()) areaLights += seenOnFilm(*light) ? 1 : 0;
  const double perLight = areaLights > 0 ? double(kFootprintPointBudget) / double(areaLights) : 0.0;
  return int(std::max(8.0, std::floor(std::sqrt(std::min(perLight, double(kFootprintPoints))))));
}

std::vector<uint8_t> smallLightCells(const RenderScene& scene, int G, uint64_t* lights) {
  const Camera& camera = scene.camera();
  const int X = camera.width() * G, Y = camera.height() * G;
  std::vector<uint8_t> marked(size_t(X) * size_t(Y), 0);
  if (lights) *lights = 0;
  const int side = footprintPointsPerSide(scene);  // side^2 points per light, stratified over sampleLe's uPos
  std::vector<uint64_t> cells;
  for (const std::unique_ptr<Light>& light : scene.lights()) {
    if (!seenOnFilm(*light)) continue;
    cells.clear();
    bool small = true;
    for (int i = 0; i < side * side && small; ++i) {
      const Vec2 uPos{(float(i % side) + 0.5f) / float(side), (float(i / side) + 0.5f) / float(side)};
      const std::optional<LightLeSample> le = light->sampleLe(uPos, Vec2{0.5f, 0.5f});
      if (!le) continue;
      const std::optional<Vec2> r = camera.rasterPosition(le->ray.o);
      if (!r) continue;
      const int cx = std::clamp(int(r->x * float(G)), 0, X - 1), cy = std::clamp(int(r->y * float(G)), 0, Y - 1);
      const uint64_t c = uint64_t(cy) * uint64_t(X) + uint64_t(cx);
      if (std::find(cells.begin(), cells.end(), c) == cells.end()) cells.push_back(c);
      small = cells.size() <= kFootprintMaxCells;
    }
    if (!small || cells.empty()) continue;  // a large light: the pilot sees it over many cells
    if (lights) ++*lights;
    for (uint64_t c : cells) {  // the footprint and its 8 neighbours (an outline the points did not reach)
      const int cx = int(c % uint64_t(X)), cy = int(c / uint64_t(X));
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = cx + dx, yy = cy + dy;
          if (xx >= 0 && yy >= 0 && xx < X && yy < Y) marked[size_t(yy) * size_t(X) + size_t(xx)] = 1;
        }
    }
  }
  return marked;
}

EmissionEstimate emissionEstimate(const RenderScene& scene, const RenderSettings& s, const TargetShape& target,
                                  bool parallel) {
  const int W = scene.camera().width(), H = scene.camera().height();  // the film
  if (W <= 0 || H <= 0) throw std::invalid_argument("emission estimate: empty film");
  IntegratorSettings oneSegment = s.integrator;
  oneSegment.maxDepth = 1;  // Le at the first hit (or an environment light on a miss); no light sampling
  const std::unique_ptr<PathEvaluator> pt = makeEvaluator(scene, "pt", oneSegment);
  // Cells: G x G per pixel, so that there are at least kEmissionMinCells.
  const int G = emissionCellsPerPixelAxis(W, H);
  const int X = W * G, Y = H * G;
  const size_t C = size_t(X) * size_t(Y);
  // A ray through cell (cx, cy) at u in the cell.
  const auto seen = [&](IndependentSource& source, PathContribution& path, int cx, int cy, Vec2 u) {
    const float ux = std::min((float(cx % G) + u.x) / float(G), kBelowOne);
    const float uy = std::min((float(cy % G) + u.y) / float(G), kBelowOne);
    return emissionSeen(*pt, source, path, cx / G, cy / G, Vec2(ux, uy));
  };

  // 1. The pilot.
  std::vector<double> pilot(C);
  forRows(Y, parallel, [&](int y) {
    IndependentSource source(0, 0);
    PathContribution path;
    for (int x = 0; x < X; ++x) {
      const uint64_t j = uint64_t(y) * uint64_t(X) + uint64_t(x);
      source.reset(hashKeys(s.seed, kPilotKey, j), 0);
      pilot[j] = seen(source, path, x, y, Vec2{source.valueAt(3, 0), source.valueAt(3, 1)});
    }
  });
  // 1b. The cells of the small lights, from their geometry (a light about a cell wide the pilot's one ray
  // per cell may miss or hit: either way its 3x3 test cannot see the light's outline).
  uint64_t smallLights = 0;
  const std::vector<uint8_t> small = smallLightCells(scene, G, &smallLights);
  uint64_t lit = 0, smallCells = 0;
  double pilotSum = 0, pilotMax = 0;  // in index order: deterministic; the max over the cells not marked
  for (size_t j = 0; j < C; ++j) {
    const double v = pilot[j];
    lit += v > 0 ? 1 : 0;
    smallCells += small[j];
    pilotSum += v;
    if (!small[j]) pilotMax = std::max(pilotMax, v);
  }
  EmissionEstimate out;
  out.cellsPerPixelAxis = G;
  out.litCells = lit;
  out.smallLights = smallLights;
  out.maxCellShare = pilotSum > 0 ? pilotMax / pilotSum : 0.0;
  out.rays = uint64_t(C);
  // Not estimated: a cell the geometry did not mark holds too much of the pilot's emission, or nothing is
  // seen (no emission in the pilot and no small light).
  if (out.maxCellShare >= kEmissionMaxCellShare || (!(pilotSum > 0) && smallCells == 0)) return out;
  out.estimated = true;
  // Cells whose 3x3 neighbourhood (clipped to the film) the pilot saw as one value are flat, unless a small
  // light's footprint marks them.
  std::vector<uint8_t> edge(C, 0);
  uint64_t edges = 0;
  for (int y = 0; y < Y; ++y)
    for (int x = 0; x < X; ++x) {
      const double v = pilot[size_t(y) * X + x];
      bool flat = !small[size_t(y) * X + x];
      for (int dy = -1; dy <= 1 && flat; ++dy)
        for (int dx = -1; dx <= 1 && flat; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx >= 0 && yy >= 0 && xx < X && yy < Y && pilot[size_t(yy) * X + xx] != v) flat = false;
        }
      edge[size_t(y) * X + x] = flat ? 0 : 1;
      edges += flat ? 0 : 1;
    }
  const double edgeBudget = kEmissionEdgeBudget * double(C);
  const uint32_t edgeRays =  // even: two replicates
      edges == 0 ? kEmissionEdgeRays
                 : uint32_t(std::clamp(std::floor(edgeBudget / double(edges)), double(kEmissionFlatRays),
                                       double(kEmissionEdgeRays))) & ~1u;

  // 2. Fresh stratified rays per cell; per-row sums of I_j^ and of its variance estimate, reduced in row order.
  std::vector<double> rowMean(size_t(Y), 0.0), rowVar(size_t(Y), 0.0);
  std::vector<double> rowLum(size_t(Y), 0.0), rowLumVar(size_t(Y), 0.0);  // luminance (a shaped target only)
  const bool weighted = target.hasMap(), shaped = target.shaped();
  const double beta = target.power;  // (T1): each ray's c = (h L_e)^beta = h^beta L_e^beta
  forRows(Y, parallel, [&](int y) {
    IndependentSource source(0, 0);
    PathContribution path;
    double sumMean = 0, sumVar = 0, sumLum = 0, sumLumVar = 0;
    for (int x = 0; x < X; ++x) {
      const uint64_t j = uint64_t(y) * uint64_t(X) + uint64_t(x);
      const uint32_t half = (edge[j] ? edgeRays : kEmissionFlatRays) / 2;
      double m[2], mc[2];  // per replicate: the mean luminance, and the mean L_e^beta (= m where beta = 1)
      for (uint64_t r = 0; r < 2; ++r) {  // two independent replicates of `half` stratified rays
        const uint64_t key = hashKeys(s.seed, kStageKey, j, r);
        double sum = 0, sumC = 0;
        for (uint32_t k = 0; k < half; ++k) {
          source.reset(key, k);
          const double v = seen(source, path, x, y, stratifiedPixelPoint(key, k, half));
          sum += v;
          if (beta != 1) sumC += std::pow(v, beta);
        }
        m[r] = sum / double(half);
        mc[r] = beta != 1 ? sumC / double(half) : m[r];
      }
      double h = weighted ? double(target.importance->at(Vec2{float(x / G) + 0.5f, float(y / G) + 0.5f})) : 1.0;
      if (beta != 1) h = std::pow(h, beta);
      const double mean = 0.5 * (mc[0] + mc[1]), var = 0.25 * (mc[0] - mc[1]) * (mc[0] - mc[1]);  // E[(m_0 - m_1)^2] / 4
      const double lum = 0.5 * (m[0] + m[1]), lumVar = 0.25 * (m[0] - m[1]) * (m[0] - m[1]);
      sumMean += h * mean;
      sumVar += h * h * var;
      sumLum += lum;
      sumLumVar += lumVar;
    }
    rowMean[size_t(y)] = sumMean;
    rowVar[size_t(y)] = sumVar;
    rowLum[size_t(y)] = sumLum;
    rowLumVar[size_t(y)] = sumLumVar;
  });
  double total = 0, var = 0, totalLum = 0, varLum = 0;
  for (int y = 0; y < Y; ++y) {
    total += rowMean[size_t(y)];
    var += rowVar[size_t(y)];
    totalLum += rowLum[size_t(y)];
    varLum += rowLumVar[size_t(y)];
  }

  out.edgeCells = edges;
  out.edgeRays = edgeRays;
  out.rays = uint64_t(C) + (uint64_t(C) - edges) * kEmissionFlatRays + edges * uint64_t(edgeRays);
  BootstrapEstimate& e = out.estimate;
  e.n = out.rays;
  e.b = total / double(C);
  e.stdErr = std::sqrt(var) / double(C);
  e.sampleVar = 0;  // set by the caller (see the header)
  e.tau = std::numeric_limits<double>::infinity();  // no tail split: the whole b_1
  e.bulkB = e.b;
  e.bulkStdErr = e.stdErr;
  e.bulkVar = 0;
  e.excessMeanSq = 0;
  if (shaped) {  // the same summary of the luminance sums
    BootstrapEstimate& l = out.luminance;
    l = e;
    l.b = l.bulkB = totalLum / double(C);
    l.stdErr = l.bulkStdErr = std::sqrt(varLum) / double(C);
  }
  return out;
}

}  // namespace mlt
