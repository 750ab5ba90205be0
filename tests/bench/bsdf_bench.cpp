// BSDF sample()/eval()/pdf() throughput: one iteration = one call at a random incident direction
// (64 directions cycled, random sample numbers). Compare GGX vs Beckmann visible-normal sampling
// (Beckmann inverts its slope CDF numerically) and the cost of rough vs smooth models.
#include <benchmark/benchmark.h>

#include <vector>

#include "common/core/rng.h"
#include "common/core/sampling.h"
#include "common/bsdf/make_bsdf.h"
#include "common/scene/scene_desc.h"

namespace mlt {
namespace {

std::unique_ptr<Bsdf> build(BsdfDesc::Type t, MicrofacetType dist = MicrofacetType::GGX, float alpha = 0.2f) {
  BsdfDesc d;
  d.type = t;
  d.id = "bench";
  d.distribution = dist;
  d.alpha = alpha;
  d.intIOR = 1.5f;
  d.extIOR = 1.0f;
  d.eta = Color(0.2f, 0.92f, 1.1f);
  d.k = Color(3.9f, 2.45f, 2.14f);
  return makeBsdf({}, d);
}

std::vector<Vec3> directions(bool bothSides) {
  Pcg32 rng(1, 2);
  std::vector<Vec3> out;
  while (out.size() < 64) {
    Vec3 w = sampleUniformSphere(rng.uniform2());
    if (!bothSides) w.z = std::fabs(w.z);
    if (std::fabs(w.z) > 0.01f) out.push_back(w);
  }
  return out;
}

void sampleBench(benchmark::State& state, BsdfDesc::Type t, MicrofacetType dist) {
  const auto bsdf = build(t, dist);
  const auto wos = directions(t == BsdfDesc::Type::RoughDielectric || t == BsdfDesc::Type::Dielectric);
  Pcg32 rng(3, 4);
  size_t i = 0;
  for (auto _ : state) {
    const float uc = rng.uniform();
    const Vec2 ud = rng.uniform2();
    benchmark::DoNotOptimize(bsdf->sample(wos[i++ & 63], uc, ud, {}));
  }
  state.SetItemsProcessed(state.iterations());
}

void evalPdfBench(benchmark::State& state, BsdfDesc::Type t, MicrofacetType dist) {
  const auto bsdf = build(t, dist);
  const auto wos = directions(t == BsdfDesc::Type::RoughDielectric);
  const auto wis = directions(true);
  size_t i = 0;
  for (auto _ : state) {
    const Vec3& wo = wos[i & 63];
    const Vec3& wi = wis[(i * 7 + 3) & 63];
    ++i;
    benchmark::DoNotOptimize(bsdf->eval(wo, wi, {}));
    benchmark::DoNotOptimize(bsdf->pdf(wo, wi, {}));
  }
  state.SetItemsProcessed(state.iterations());
}

using T = BsdfDesc::Type;
BENCHMARK_CAPTURE(sampleBench, diffuse, T::Diffuse, MicrofacetType::GGX);
BENCHMARK_CAPTURE(sampleBench, dielectric, T::Dielectric, MicrofacetType::GGX);
BENCHMARK_CAPTURE(sampleBench, plastic, T::Plastic, MicrofacetType::GGX);
BENCHMARK_CAPTURE(sampleBench, roughconductor_ggx, T::RoughConductor, MicrofacetType::GGX);
BENCHMARK_CAPTURE(sampleBench, roughconductor_beckmann, T::RoughConductor, MicrofacetType::Beckmann);
BENCHMARK_CAPTURE(sampleBench, roughdielectric_ggx, T::RoughDielectric, MicrofacetType::GGX);
BENCHMARK_CAPTURE(sampleBench, roughdielectric_beckmann, T::RoughDielectric, MicrofacetType::Beckmann);
BENCHMARK_CAPTURE(sampleBench, roughplastic_ggx, T::RoughPlastic, MicrofacetType::GGX);
BENCHMARK_CAPTURE(evalPdfBench, diffuse, T::Diffuse, MicrofacetType::GGX);
BENCHMARK_CAPTURE(evalPdfBench, roughconductor_ggx, T::RoughConductor, MicrofacetType::GGX);
BENCHMARK_CAPTURE(evalPdfBench, roughdielectric_ggx, T::RoughDielectric, MicrofacetType::GGX);
BENCHMARK_CAPTURE(evalPdfBench, roughdielectric_beckmann, T::RoughDielectric, MicrofacetType::Beckmann);
BENCHMARK_CAPTURE(evalPdfBench, roughplastic_ggx, T::RoughPlastic, MicrofacetType::GGX);

}  // namespace
}  // namespace mlt

BENCHMARK_MAIN();
