// Markov chain jobs (mlt_job.h): development. b per path length refined by the large steps merged so far
// (develop.h (D3)-(D6)), the splat layers' scales ((D1), (D2), (D7), (D8)) and the image.
#include "common/job/mlt_job.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "common/mlt/strata.h"

namespace mlt {

namespace {
// (D3)-(D5) per slot from the bootstrap's estimates and the large steps' sums (strata: the slot's (D6)
// strata, or none), and their total with the slots' standard errors in quadrature.
template <typename Strata>
RefinedB refineSlots(const std::vector<BootstrapEstimate>& boot, const std::vector<TargetSums>& large,
                     const Strata& strataOf) {
  RefinedB r;
  const size_t slots = std::max(boot.size(), large.size());
  r.perSlot.resize(slots);
  double var = 0;
  for (size_t l = 0; l < slots; ++l) {
    const TargetSums sums = l < large.size() ? large[l] : TargetSums{};
    const StratifiedMean strata = strataOf(l, sums);
    r.perSlot[l] = combineB(l < boot.size() ? boot[l] : BootstrapEstimate{}, sums, strata.valid ? &strata : nullptr);
    r.total.b += r.perSlot[l].b;
    r.total.samples += r.perSlot[l].samples;
    var += r.perSlot[l].stdErr * r.perSlot[l].stdErr;
  }
  r.total.stdErr = std::sqrt(var);
  return r;
}
}  // namespace

RefinedB refinedLuminanceB(const Normalization& norm, const ChainStats& merged) {
  return refineSlots(norm.bootstrapLuminance, merged.largeStepLuminanceSums,
                     [](size_t, const TargetSums&) { return StratifiedMean{}; });
}

RefinedB refinedB(const Normalization& norm, const ChainStats& merged, const Film* film) {
  return refineSlots(norm.bootstrapB, merged.largeStepSums, [film](size_t l, const TargetSums& large) {
    StratifiedMean strata;  // (D6), where the chains kept strata
    if (film && film->hasSplatLayer(bStrataLayer(l)) && large.n > 0)
      strata = postStratifiedMean(film->splatLayer(bStrataLayer(l)), film->width(), film->height());
    if (strata.valid && strata.n != large.n) strata.valid = false;  // every large step, once, or none
    return strata;
  });
}

std::vector<Color> developMarkovChainImage(const JobPlan& plan, const PartialResult& merged) {
  if (merged.film.pixelCount() == 0) return developMarkovChainImage(plan, merged, {});  // zeros, or the error
  return developMarkovChainImage(plan, merged, markovChainLayerScales(plan, merged));
}

std::vector<Color> developMarkovChainImage(const JobPlan& plan, const PartialResult& merged,
                                           const std::vector<double>& scales) {
  const RenderSettings& s = plan.settings;
  const size_t P = size_t(s.width) * size_t(s.height);
  if (merged.film.pixelCount() == 0) {
    if (plan.units.empty()) return std::vector<Color>(P);  // b = 0: nothing carries light
    throw std::invalid_argument("developImage: no work units merged");
  }
  return merged.film.develop(scales);
}

namespace {
// (D8): each slot's chain and large-step layers scaled together so that the slot's image holds P b_lum^ of
// luminance, b_lum^ pooled from the bootstrap's luminance and the large steps' (refinedLuminanceB).
void scaleToLuminance(const Normalization& norm, const PartialResult& merged, std::vector<double>& scales) {
  const Film& film = merged.film;
  const double P = double(film.width()) * double(film.height());
  const RefinedB lum = refinedLuminanceB(norm, merged.stats);
  const size_t slots = norm.mutationsPerLength.size();
  const auto layerLuminance = [&](size_t layer) {  // sum over pixels, as luminance() weighs colours
    if (layer >= scales.size() || scales[layer] == 0 || !film.hasSplatLayer(layer)) return 0.0;
    const PixelBuffer& sums = film.splatLayer(layer);
    double total = 0;
    for (size_t i = 0; i < sums.size(); ++i)
      total += double(luminance(Color(1, 0, 0))) * sums[i].r + double(luminance(Color(0, 1, 0))) * sums[i].g +
               double(luminance(Color(0, 0, 1))) * sums[i].b;
    return total * scales[layer];
  };
  for (size_t slot = 0; slot < slots && slot < lum.perSlot.size(); ++slot) {
    const size_t chain = chainLayer(slot), large = largeStepLayer(slot, slots);
    const double developed = layerLuminance(chain) + layerLuminance(large);
    if (!(developed > 0) || !(lum.perSlot[slot].b > 0)) continue;  // nothing to scale (the image keeps its zeros)
    const double r = lum.perSlot[slot].b * P / developed;
    for (size_t layer : {chain, large})
      if (layer < scales.size()) scales[layer] *= r;
  }
}
}  // namespace

std::vector<double> markovChainLayerScales(const JobPlan& plan, const PartialResult& merged) {
  const RenderSettings& s = plan.settings;
  const size_t P = size_t(s.width) * size_t(s.height);
  // Layer 0: the direct pass's t = 1 splats, P / N with N the light paths of the direct units merged.
  uint64_t directLightPaths = 0;
  for (uint32_t i : merged.units)
    if (i < plan.units.size() && isDirectUnit(plan.units[i]))
      directLightPaths += uint64_t(plan.units[i].sampleEnd - plan.units[i].sampleBegin) * P;
  std::vector<double> scales(merged.film.splatLayerCount(), 0.0);
  if (directLightPaths > 0) scales[0] = double(P) / double(directLightPaths);
  // chainLayer(slot): (D2) with b_k pooled from bootstrap and large steps (D3) and M_k the mutations of that
  // length merged (all of them once every chain is in; a preview's are a subset, still exact per length).
  const RefinedB refined = refinedB(plan.norm, merged.stats, &merged.film);
  const auto& M = merged.stats.proposedPerLength;
  for (size_t slot = 0; slot < M.size() && chainLayer(slot) < scales.size(); ++slot)
    if (M[slot] > 0 && slot < refined.perSlot.size())
      scales[chainLayer(slot)] = chainSplatScale(refined.perSlot[slot].b, M[slot], P);
  // largeStepLayer(slot) (Kelemen MIS, (D7)): the b the chains weighted by, the bootstrap's, and the same M_k.
  const Normalization& norm = plan.norm;
  const size_t slots = norm.mutationsPerLength.size();
  for (size_t slot = 0; slot < M.size() && slot < slots && largeStepLayer(slot, slots) < scales.size(); ++slot)
    if (M[slot] > 0) scales[largeStepLayer(slot, slots)] = chainSplatScale(norm.weightB(slot), M[slot], P);
  if (norm.target().shaped()) scaleToLuminance(norm, merged, scales);  // (D8)
  return scales;
}

}  // namespace mlt
