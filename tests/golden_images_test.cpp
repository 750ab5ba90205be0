// Golden digests ("what must show"): every method renders the bundled scenes at a fixed seed and a tiny
// budget through the job API (planJob -> runWorkUnit for every unit in index order -> PartialResult::add
// -> developImage), and the SHA-256 of the developed image's floats (r, g, b per pixel, row-major) must
// equal the digest recorded below. The job API promises bit-identical images for any thread count, so a
// digest changes only when the arithmetic of some path changes.
//
// Re-recording: on a mismatch the test prints the new digest as a table line to paste below.
//  - pt, lt, bdpt: a refactor (moving files, splitting classes, renaming) must never change these. A
//    mismatch means behaviour changed; re-record only for a deliberate change to the estimator itself.
//  - pssmlt, pssmlt-bdpt, mmlt: also expected to be re-recorded when the Markov-chain normalization (the
//    bootstrap's b, per-length b_k, development) changes on purpose; say so in the commit message.
//    (Re-recorded so far: b refined by the large steps, candidates with spread film positions, one film
//    layer per path length; then candidates with spread technique and light coordinates. pt/lt/bdpt
//    unchanged by either.)
//  - Every method on glossy-plates and caustic-mirror (pt/lt/bdpt included) was re-recorded once for a
//    deliberate change of the area light's position sampling: meshes of more than 16 triangles pick their
//    triangle in two levels (area_light.cpp; same density, other numbers for the same u).
//  - mmlt on every scene: mutations allocated to path lengths by allocationWeights (common/mlt/allocation.h) instead
//    of in proportion to b_k.
//  - mmlt on cornell-box and caustic-mirror, pssmlt on cornell-variety: the bootstrap's budget counts the
//    candidates' cost (numbers drawn) against the chains' mix (bootstrap.h, chainMixCost), so its size
//    changed there; the other chain jobs kept their bootstrap and their digests.
//  - pssmlt, pssmlt-bdpt, mmlt on every scene: b_k split at the bootstrap's tail threshold, the bulk
//    combined by inverse variance and the excess pooled by count (develop.h (D3)-(D5); the weights on all of
//    c biased b low).
//
// rjmlt and veach-mlt were added to the table when they existed (2026-12-03), with the b of develop.h's tail
// split.
//  - Every chain method on every scene: pssmlt, pssmlt-bdpt and veach-mlt for b's large steps (veach-mlt's
//    b samples) post-stratified by film position (develop.h (D6)); mmlt and rjmlt, which keep no strata,
//    for their chain layers renumbered 1 + 2k (the stochastic rounding keys changed with the layer).
//    pt/lt/bdpt unchanged.
//  - mmlt and rjmlt where a light is seen directly (cornell-box, cornell-variety): b_1 from camera rays
//    (common/job/emission_estimate.h) instead of the candidates of length 1, whose count the bootstrap's
//    budget then no longer grows (BootstrapConfig::seedOnlyLengths). glossy-plates (a light ~1 pixel wide:
//    the candidates' b_1 is kept, kEmissionMaxCellShare) and caustic-mirror (no light in view) keep their
//    digests, as does every other method.
//  - Every method on every scene but caustic-mirror's lt: Embree's kernels capped at AVX2 (accel.cpp: its
//    AVX-512 kernels, on which the digests had been recorded, give other bits; a farm must give the same
//    bytes on every worker). The same image up to those bits.
//  - pssmlt, pssmlt-bdpt, mmlt and rjmlt on every scene: a vertex reads only the BSDF numbers its BSDF
//    uses (Bsdf::reads, integrators/bsdf_numbers.h: none on a mirror, no lobe choice on a diffuse
//    surface), so the chains draw other random numbers. pt, lt, bdpt (the same numbers by index) and
//    veach-mlt (its own path numbers) unchanged.
//  - pssmlt, pssmlt-bdpt, mmlt and rjmlt on every scene: Kelemen MIS splatting is their default (chain.h),
//    its large steps' share in a layer of its own developed with the bootstrap's b (develop.h (D7));
//    veach-mlt (expected values) and pt/lt/bdpt unchanged.
//  - veach-mlt on every scene: its lens and caustic perturbations' selection weights are 2 (mutations.h).
//  - veach-mlt on every scene: the light-view pass (common/methods/veach/light_view.h; the paths E S* L
//    by camera rays, left out of the chains and of their b). Every other method unchanged.
//  - veach-mlt on caustic-mirror: the bidirectional mutation rejects before tracing a proposal whose
//    connection end would be a mirror or glass vertex (bidir.cpp; f was zero there anyway), so its chains
//    draw fewer random numbers. The same chain kernel; cornell-box (no Dirac surface) keeps its digest.
//  - mmlt and rjmlt on every scene: the bootstrap's budget prices the chains' mutations by the plan's mix of
//    path lengths (allocation.h, mutationWeights) instead of b_k alone, and counts b_1's camera rays
//    (BootstrapConfig::spentCost), so their bootstraps changed size. Every other method unchanged.
//  - pssmlt-bdpt, mmlt and rjmlt on cornell-box and cornell-variety, veach-mlt on cornell-box: the direct
//    light's default is automatic (common/job/direct_light_rule.h), and the pilot takes a bdpt pass there.
//    Where it does not (glossy-plates, caustic-mirror; veach-mlt on cornell-variety) and for pssmlt, which
//    cannot render it apart, the digests are unchanged: the pilot draws numbers of its own.
//  - The same seven again: the direct pass is pt instead of bdpt, and twice as large (kDirectPassMethod,
//    kDirectSppPerMutation). The chains are the same; every other digest unchanged.
//  - pssmlt-bdpt on cornell-box, and pssmlt-bdpt, mmlt and rjmlt on cornell-variety: the pass's size
//    follows the pilot's share of the light in the pass's paths (mlt_job.h, directSppPerMutation;
//    pssmlt-bdpt's mutations priced at 4 of mmlt's), and the pilot's share takes 4096 samples instead of
//    1024. The other three with a pass got the same spp at this budget;
//    where the pilot keeps the chains the digests are unchanged.
//  - Every bidirectional method (bdpt, pssmlt-bdpt, mmlt, rjmlt, veach-mlt) where its camera subpaths
//    reach a second vertex: the first vertex's densities come with the camera ray (CameraRay::pdfDir, from
//    the direction in camera space) instead of pdfWe's second pass over the ray: the same density up to
//    rounding, and no longer zero for a ray from the film's very edge. pt, lt and pssmlt unchanged; on
//    caustic-mirror every digest came out unchanged (not investigated why).
//  - mmlt, rjmlt and (a commit later) pssmlt-bdpt on glossy-plates: three of its four spheres are small
//    on the film, so the bootstrap renders the lights seen directly by a pt pass at stratified pixel
//    points, 16x as many around the small lights (DirectLight::Emission, mlt_job.h), and the chains leave
//    out the paths of one segment. Every other digest
//    unchanged (no other bundled scene has a small light in view, and where the chains keep length 1
//    b_1's rays only change with one).
//  - Every method but lt on glossy-plates and caustic-mirror (their lights are spheres): next-event
//    estimation samples a sphere light by the solid angle it subtends (area_light.cpp, (C1)), and bdpt's
//    MIS weight gives the strategy s = 1 that density (misWeight's k). lt (sampleLe only) unchanged.
//  - pssmlt on glossy-plates: pt and bdpt find a sphere light's point and its visibility with one ray
//    through the scene (Light::sampleLiVisible), which leaves ref's surface by tMin along the ray instead
//    of the shadow ray's offset along the normal: the same points, and a verdict that differs in a few
//    samples in ten thousand (tests/sphere_light_test.cpp), one of them in this chain. Every other digest
//    unchanged.
//  - pt and bdpt on every scene, and the chain methods whose plan has a direct pass (pssmlt-bdpt, mmlt,
//    rjmlt on cornell-box and cornell-variety, veach-mlt on cornell-box): a camera sample's position in
//    its pixel is the pixel's Sobol point (sobolPixelPoint, sample_job.h) instead of two hashed numbers.
//    lt (no camera samples) and the chains themselves unchanged.
//  - veach-mlt on glossy-plates: the light-view pass's samples of a pixel at its Sobol points too
//    (light_view.cpp). Where no light-view sample carries light at this budget the digest is unchanged.
//  - mmlt and rjmlt on every scene: the image's b_k is developed from the bootstrap's first round (the
//    candidates whose count no value decided: bootstrap.h, LengthBootstrap::fixedCount) and the large steps,
//    no longer from every candidate (the sizing's later rounds biased b_k low). The chains are unchanged
//    (allocation, starts and Kelemen weights still use every candidate); one-length methods keep every
//    candidate and their digests.
//  - rjmlt on cornell-box, caustic-mirror, glossy-plates and cornell-variety: --technique-step's default 0.05
//    -> 0.02 (docs/SWEEP.md): a move draw in [0.12, 0.15) is now a small step, not a technique change. The
//    other rjmlt digests are the same at this size.
//
// Besides scenes/*.xml as they are, "cornell-variety" is cornell-box.xml with the BSDFs, lights and
// camera the bundled scenes do not use (plastic, rough plastic, rough and thin dielectric, two-sided
// conductor; point, spot, directional and constant lights; thin lens), so every concrete type is covered.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

#include "common/core/sha256.h"
#include "common/methods/registry.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"

namespace mlt {
namespace {

constexpr int kRes = 32;

struct Case {
  const char* scene;   // scenes/<scene>.xml, or "cornell-variety"
  std::string method;
  const char* digest;  // SHA-256 of the developed image's float bytes
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.scene << " " << c.method.c_str(); }

// cornell-box.xml with every concrete type the bundled scenes leave out. Mesh order is the file's shape
// order: floor, ceiling, back, left, right, short box, tall box, light.
SceneDesc cornellVariety() {
  SceneDesc d = loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/cornell-box.xml");
  auto addBsdf = [&](BsdfDesc b) {
    b.id = "variety-" + std::to_string(d.bsdfs.size());
    d.bsdfs.push_back(b);
    return int(d.bsdfs.size()) - 1;
  };
  BsdfDesc plastic;
  plastic.type = BsdfDesc::Type::Plastic;
  plastic.reflectance.value = Color(0.6f, 0.55f, 0.5f);
  plastic.nonlinear = true;
  BsdfDesc roughPlastic = plastic;
  roughPlastic.type = BsdfDesc::Type::RoughPlastic;
  roughPlastic.distribution = MicrofacetType::GGX;
  roughPlastic.alpha = 0.2f;
  roughPlastic.nonlinear = false;
  roughPlastic.reflectance.type = TextureDesc::Type::Checkerboard;
  roughPlastic.reflectance.uvScale = Vec2{4, 4};
  BsdfDesc roughGlass;
  roughGlass.type = BsdfDesc::Type::RoughDielectric;
  roughGlass.distribution = MicrofacetType::Beckmann;
  roughGlass.alpha = 0.3f;
  BsdfDesc thinGlass;
  thinGlass.type = BsdfDesc::Type::ThinDielectric;
  BsdfDesc gold;
  gold.type = BsdfDesc::Type::Conductor;
  gold.eta = Color(0.143f, 0.374f, 1.442f);
  gold.k = Color(3.983f, 2.385f, 1.603f);
  BsdfDesc twoSided;
  twoSided.type = BsdfDesc::Type::TwoSided;
  twoSided.nested = addBsdf(gold);
  d.meshes[0].bsdf = addBsdf(plastic);       // floor
  d.meshes[3].bsdf = addBsdf(roughPlastic);  // left wall
  d.meshes[5].bsdf = addBsdf(roughGlass);    // short box
  d.meshes[6].bsdf = addBsdf(twoSided);      // tall box
  d.meshes[2].bsdf = addBsdf(thinGlass);     // back wall

  LightDesc point;
  point.type = LightDesc::Type::Point;
  point.position = Vec3{0.5f, 1.6f, 0.5f};
  point.intensity = Color(0.8f, 0.7f, 0.5f);
  LightDesc spot;
  spot.type = LightDesc::Type::Spot;
  spot.position = Vec3{-0.6f, 1.8f, 0.8f};
  spot.direction = normalize(Vec3{0.3f, -1.0f, -0.4f});
  spot.intensity = Color(3.0f);
  spot.cutoffAngleDeg = 30;
  spot.beamWidthDeg = 20;
  LightDesc sun;
  sun.type = LightDesc::Type::Directional;
  sun.direction = normalize(Vec3{0.2f, -0.3f, -1.0f});  // through the open front
  sun.intensity = Color(1.5f, 1.4f, 1.2f);
  LightDesc sky;
  sky.type = LightDesc::Type::Constant;
  sky.intensity = Color(0.2f, 0.25f, 0.3f);
  d.lights = {point, spot, sun, sky};

  d.camera.type = CameraDesc::Type::ThinLens;
  d.camera.apertureRadius = 0.05f;
  d.camera.focusDistance = 5.0f;
  return d;
}

// The digest of the image, and its mean luminance (so a black or non-finite image is not recorded unnoticed).
std::string renderDigest(const Case& c, double* mean) {
  SceneDesc desc = std::string(c.scene) == "cornell-variety"
                       ? cornellVariety()
                       : loadMitsubaScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + c.scene + ".xml");
  desc.camera.width = desc.camera.height = kRes;
  const auto scene = RenderScene::build(desc);
  RenderSettings s;
  s.method = c.method;
  s.seed = 20240601;
  s.width = s.height = kRes;
  s.integrator.maxDepth = desc.maxDepth.value_or(5);
  s.integrator.rrDepth = desc.rrDepth.value_or(5);
  s.spp = 4;
  s.samplesPerUnit = 2;
  s.mutationsPerPixel = 4;
  s.chains = 4;
  s.bootstrapSamples = 4000;
  const JobPlan plan = planJob(*scene, s);
  PartialResult merged;
  for (const WorkUnit& u : plan.units) merged.add(runWorkUnit(*scene, plan, u));
  const std::vector<Color> img = developImage(plan, merged);
  Sha256 h;
  *mean = 0;
  for (const Color& p : img) {
    *mean += luminance(p) / double(img.size());
    const float rgb[3] = {p.r, p.g, p.b};
    h.update(rgb, sizeof rgb);
  }
  return h.hexDigest();
}

class GoldenImages : public ::testing::TestWithParam<Case> {};

TEST_P(GoldenImages, DigestMatches) {
  const Case c = GetParam();
  double mean = 0;
  const std::string got = renderDigest(c, &mean);
  std::printf("%s %s: mean %.6g, digest %s\n", c.scene, c.method.c_str(), mean, got.c_str());
  // caustic-mirror under lt is black by design: the camera sees the room only in a mirror, and light
  // tracing cannot connect to the camera through a specular vertex.
  const bool black = std::string(c.scene) == "caustic-mirror" && c.method == "lt";
  EXPECT_TRUE(std::isfinite(mean) && (black ? mean == 0 : mean > 0)) << "mean luminance " << mean;
  EXPECT_EQ(got, c.digest) << "new digest; if the change is deliberate, re-record with:\n    Case{\"" << c.scene
                           << "\", \"" << c.method << "\", \"" << got << "\"},";
}

// Recorded on f92bac3 (x86-64, gcc, the Release flags of CMakeLists.txt); unchanged by the move of the
// interfaces to common/interfaces (37ad07d). Another compiler or -march may round differently.
const Case kCases[] = {
    Case{"cornell-box", "pt", "49345801ed0f37a9c77aaa01b77a84f0247fa1be9b2ae9a685b681dcbf433a6c"},
    Case{"cornell-box", "lt", "aac1d685dbcbddd5940fe1adc62a37adce95225788e2baf91d2b8172fc75016b"},
    Case{"cornell-box", "bdpt", "ae0358f74b9772b87f2a5a9a3322f522d5e674c098dfb57f46b42a25a0c6e9e4"},
    Case{"cornell-box", "pssmlt", "3b5e17ca6842106c16947553d3d0191a194e2e475ef08af3fa96cb9f103e7405"},
    Case{"cornell-box", "pssmlt-bdpt", "671e468962476209c008b870eef0be4fcf8b6988382ddfb9a86cc1e59553ffcc"},
    Case{"cornell-box", "mmlt", "a09cf45105211234d1f2a9a7fc5e0d57a39dfcff38e203b62d42e996cb88ae66"},
    Case{"caustic-mirror", "pt", "fdb2510969422b355100d947eeaeb36e9c1915032797b7284799d57a65bab618"},
    Case{"caustic-mirror", "lt", "f3cc103136423a57975750907ebc1d367e2985ac6338976d4d5a439f50323f4a"},
    Case{"caustic-mirror", "bdpt", "bf6c6ddb7518110d2ed686e0d7bdee372e1400b5dd092da72276d6574e16fec6"},
    Case{"caustic-mirror", "pssmlt", "9abbf4f23a18e33a7d88cabf8fbdc3cb68875564bb7a27d8885043fe9462eb94"},
    Case{"caustic-mirror", "pssmlt-bdpt", "5d6b1b80611af77a495245d15b600364236383cb8f5cab7a52c328de337883fa"},
    Case{"caustic-mirror", "mmlt", "064c60708731d875e4a3d4bdb4809af0302d5a684b4535c0e44afc3c43846017"},
    Case{"glossy-plates", "pt", "cd92894675c97af4e6e5d83c964e939584796ff3cf62b2ef371474b2377fddcf"},
    Case{"glossy-plates", "lt", "30c49b64e9e3551e9215d5e0c4f9e8a239c65302411f35664ba18e8ca1bb1d04"},
    Case{"glossy-plates", "bdpt", "3d058b3268176812904364d0ec551f8e6e190e97e6f32daba91003fe8b852920"},
    Case{"glossy-plates", "pssmlt", "9d3c3dee6ac804af007e5d8939abe00f1595350522e6ed49b87371819efae27b"},
    Case{"glossy-plates", "pssmlt-bdpt", "a07c5f4e8101e630ad563f0607a7541cc3cf39602b6fedeaa925375c2c037fa7"},
    Case{"glossy-plates", "mmlt", "ded5b5ad6ae325a123a879d685c80c43b22204d186f83a4a18309b5bd128bc3f"},
    Case{"cornell-variety", "pt", "3d9d557ab4f7a6b5dd87016da6a8467dbb772905e49e2c5c66de04b00a41fab2"},
    Case{"cornell-variety", "lt", "284263e3fa7491c1e5dad53bf536982ecff1db2bbcbb140e9cba25fdbd48bca6"},
    Case{"cornell-variety", "bdpt", "da9c615baf953d5d20ac305d1d741c50d6d3c9c03821638ebf09712c52dbb323"},
    Case{"cornell-variety", "pssmlt", "19a4dd05d795f194fc42d7a91cee09443ebb962a49333d8c844f5c5715995cd4"},
    Case{"cornell-variety", "pssmlt-bdpt", "45ed14c33bdd83985409816878b033a1e76e1503d2a0629e9168b795f302ac76"},
    Case{"cornell-variety", "mmlt", "6b4359a8b9d8ff9d73f964153679d6b94dc31bebde5c07dd8968a2d1456cb541"},
    Case{"cornell-box", "rjmlt", "65acc7bbb79c98a49a267488d3f78cc3ee3e35656b0ad46d2f42cf36ccd63c84"},
    Case{"caustic-mirror", "rjmlt", "765811ea43a428babe2df0f614563f656ad5ae815e669a80bb8db5324e36c760"},
    Case{"glossy-plates", "rjmlt", "29c77ba05c69580b4bec76ff65839dc68a790d88cc421ec4bab9e84dd2d68051"},
    Case{"cornell-variety", "rjmlt", "43e625fd33d11c8cc91955a28fea54e1e16a6620b92f7a3851167014fc9df13a"},
    Case{"cornell-box", "veach-mlt", "2f0d4779269e0cf7865c2e2fdd232c6bf6fb663b6935f2523aebf902e0773f8f"},
    Case{"caustic-mirror", "veach-mlt", "30b75a0bd5286ec3c752cde7b88dc34278a19d51d552edd09ebe64f95e8f711e"},
    Case{"glossy-plates", "veach-mlt", "beab8ab739f3d8b5ed1f2e612739a9ad1e9107729c4bc348282e53103a142649"},
    // cornell-variety has a directional light, which veach-mlt refuses with a clear error (area, point and
    // spot lights only), so it has no veach-mlt case.
};

INSTANTIATE_TEST_SUITE_P(Bundled, GoldenImages, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           std::string n = std::string(info.param.scene) + "_" + info.param.method.c_str();
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

}  // namespace
}  // namespace mlt
