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
    Case{"cornell-box", "pt", "ea3370e2cc417deef459e000659fd68847d7acc25be4328637372e6cb878fd86"},
    Case{"cornell-box", "lt", "aac1d685dbcbddd5940fe1adc62a37adce95225788e2baf91d2b8172fc75016b"},
    Case{"cornell-box", "bdpt", "19e44f5ee9a6a65d66f3f3683d31d73c905c14a4c5b4ff3e1d57be0037ddc9e4"},
    Case{"cornell-box", "pssmlt", "ef8317bc4767724fcbb5fda5e056a3ee9a0fbda0a2273ac4920390f79ba028ac"},
    Case{"cornell-box", "pssmlt-bdpt", "4122aee77224cf828a05538c35967ae46b7dd458418be7d3ec5856de95241b5a"},
    Case{"cornell-box", "mmlt", "d3b08e113df76ec60f7a1b4f86a5e7eed34350d9ae14f67d0b16453d7ba2be03"},
    Case{"caustic-mirror", "pt", "1f47d49c9699d18775c3fea75c4e03076cdc895d83bad773cec3c631845d6cd1"},
    Case{"caustic-mirror", "lt", "f3cc103136423a57975750907ebc1d367e2985ac6338976d4d5a439f50323f4a"},
    Case{"caustic-mirror", "bdpt", "a5f0f9af415ee839e134ab51f79efa44d8775b351c400cfc76e6a8ba351512a9"},
    Case{"caustic-mirror", "pssmlt", "c9fc8a5ad18c75bd74404aca737c10bed7a58c1ed5c10bd67f6664553cb1b6b5"},
    Case{"caustic-mirror", "pssmlt-bdpt", "db3f01cef2a4e99ec70affca3a2380e53d9b13b5861379108d96c51a1d5ad170"},
    Case{"caustic-mirror", "mmlt", "6fe88b6bd17ce189271a0329cce437a49f76f065a0197638e2faa6fa7274d805"},
    Case{"glossy-plates", "pt", "4e541daf4d331318e90cd9546e0799140b3e884341ed8e26e8a6d7ebf7601462"},
    Case{"glossy-plates", "lt", "30c49b64e9e3551e9215d5e0c4f9e8a239c65302411f35664ba18e8ca1bb1d04"},
    Case{"glossy-plates", "bdpt", "d06e5116ddb56555d63da3d33f04168710620a74af374296c9eeb29b00845d4d"},
    Case{"glossy-plates", "pssmlt", "9d2b6fd10dc02e7738f877aa323b0580acd04969fedde4b851a2fd73539b0d0e"},
    Case{"glossy-plates", "pssmlt-bdpt", "fd46de0afc157d193178122fa6c39eef891ab8aca7345da01ce2dadd8c1df6cb"},
    Case{"glossy-plates", "mmlt", "332d50f5bf546c01af84f9c311677b32d056ec11e447113e1df679db8abc27a3"},
    Case{"cornell-variety", "pt", "26873108e60b97e48986560bfac8ea037b6f8323e9a0265cf15f645ba43bcef1"},
    Case{"cornell-variety", "lt", "284263e3fa7491c1e5dad53bf536982ecff1db2bbcbb140e9cba25fdbd48bca6"},
    Case{"cornell-variety", "bdpt", "567a7a36a7eb29d624ac83ba717b88bc55936cf8bd2fa07b5d4f501b68fbfda3"},
    Case{"cornell-variety", "pssmlt", "6b5e05fbd403a2a715ee3c23bd92309bc72dc7a19fba48edb7690847b5a749d5"},
    Case{"cornell-variety", "pssmlt-bdpt", "3c5ea9f179b75c8f85b13e105b604fb9ed7b8a671799bdbaa9661f85bfed814e"},
    Case{"cornell-variety", "mmlt", "008d29b37fa75b798cadf2f08f654b1bb3cafd5bbb3f2de68a4a1c7725895873"},
    Case{"cornell-box", "rjmlt", "928ae321988cd9c24472e7e640bc0b1ace76e0934557cbaee951a714fb203685"},
    Case{"caustic-mirror", "rjmlt", "f1673290bd9f401f70d3ad1a63e88e2d5e737c80d427f2481403aa9ee229fff4"},
    Case{"glossy-plates", "rjmlt", "c657067a811006e5ffb0b9e6c7054bfdf489e83cce6dc5577f77cbe6af484a3d"},
    Case{"cornell-variety", "rjmlt", "3106e6df860956d33d86d616b0176f4fcaff2a7e90bf47b64f2f8574e64f3079"},
    Case{"cornell-box", "veach-mlt", "10fdc945cd5118a698ff5a29b273148b7bfd392f96bf018c2ff40bd02840dc7e"},
    Case{"caustic-mirror", "veach-mlt", "758dca418217312995a2204d2b7e0030c3620f6fd402e0780ec26eb5fd6457af"},
    Case{"glossy-plates", "veach-mlt", "7d956680fe78e854c13919c4a7daf77068aac266ef9f7f4aa7f78fa27b99a372"},
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
