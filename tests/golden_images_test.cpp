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
//  - mmlt on every scene: mutations allocated to path lengths by allocationWeights (mlt_job.h) instead
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
    Case{"cornell-box", "pt", "e2477efacf36854d0f6c931f162502b23e1a5ef02fa117232aba30912ede9d4d"},
    Case{"cornell-box", "lt", "27913ec2dcea2a849f89b4540baaa5671551030562d72ac315cb72c056568970"},
    Case{"cornell-box", "bdpt", "3b54b9f78d4a2c8402ebe93375b4779a50b84654ac6960f31ad2e7f46dbd12d7"},
    Case{"cornell-box", "pssmlt", "0ef8bfe0fb2003db1856a2402f1023d9dc02f04da471bd52f0e82563d98bd719"},
    Case{"cornell-box", "pssmlt-bdpt", "d6d428d27e514dd6764bf4b4d28d2eb5d8f8ccc3dabd74c4df1e943b034dddeb"},
    Case{"cornell-box", "mmlt", "fd6c5b77a3618dc7d599664fb8a8dc7b15219f44f2578132ddc1234529519ac3"},
    Case{"caustic-mirror", "pt", "3723f4618b74a301f9d12494536d2ef877a4b557ab8bf89a74b86cc8865e08e8"},
    Case{"caustic-mirror", "lt", "f3cc103136423a57975750907ebc1d367e2985ac6338976d4d5a439f50323f4a"},
    Case{"caustic-mirror", "bdpt", "2e551b84c146d4ee9d8b59508f5c14e52b01e1cac35d3a595a4be731e3c8dc48"},
    Case{"caustic-mirror", "pssmlt", "ce1c45bb8b2663995ffb8b1c07620074b31c323a5c675591cdbf249386b56e0e"},
    Case{"caustic-mirror", "pssmlt-bdpt", "1e51268609dfb4d301cef9fa2a875816827c828276eeb4c9134c28fd6b7a4518"},
    Case{"caustic-mirror", "mmlt", "cb5351386374c9d93e0ba00d312ed18a60e98ee74a258f50d2642d102502e213"},
    Case{"glossy-plates", "pt", "3e1d8606c1b9797535dd32b0bc0827e2fc6c6090d310b63a1999c98d8c6d1b17"},
    Case{"glossy-plates", "lt", "103658087ff52c3db233f55efb79121213e3e6d6abd21f68cad1f85490f541c5"},
    Case{"glossy-plates", "bdpt", "5531aed294d6cbed77b813522d03d1930c6077c6397cf5f244101b74d1982dee"},
    Case{"glossy-plates", "pssmlt", "f02efab0622a388d4a0dcb42e692917cc36fd54a6cb42ebdfec5498865e520d1"},
    Case{"glossy-plates", "pssmlt-bdpt", "59fc2f9cebbbd7967088f4eca4452ed5766ab3521e6d003b2299e48213029d72"},
    Case{"glossy-plates", "mmlt", "00cf19e036a8d31c6eb91fc24868306455988cf53c916b4abf21ce935101e565"},
    Case{"cornell-variety", "pt", "d4eeb0de6b9ef719c31f3b7fde06055b03d456e53255e8da96d150906a1e9a1e"},
    Case{"cornell-variety", "lt", "f7100b968787a51b00e2ea9d2a121049e63a8d49fdaff9a44f0496e80354e377"},
    Case{"cornell-variety", "bdpt", "7294ed50043f0f0481db77cce1fc57bdbe5c4dc4140222d4a51926840e07ccaf"},
    Case{"cornell-variety", "pssmlt", "65bba77d6d1218ac45b4441985399d4636a07f819647f988533db148bdd34726"},
    Case{"cornell-variety", "pssmlt-bdpt", "ef0666784cf4b52d02f18e72ed0f46122bf1671a902f7e2564676206c66543b9"},
    Case{"cornell-variety", "mmlt", "dda95fa9293e966231daea659aac3c4317d5047e27e7f7095fe89aa869988fa2"},
    Case{"cornell-box", "rjmlt", "21d704dfd1ff9ab23635e8cee934e4714c00b2911b6df25f8fe818a90302ef15"},
    Case{"caustic-mirror", "rjmlt", "541791ba0add3e4a5607bc651f1a2304d7458e925ce3178a180d725c7ffeff5e"},
    Case{"glossy-plates", "rjmlt", "acd9563cf2d8545e1797f1a28cf618c01a419e86153054b5caa693833b390086"},
    Case{"cornell-variety", "rjmlt", "1f03b69f1cb029a80c2642d1c1ae119a84a5fa6666dbf59e70333f94c7ce840e"},
    Case{"cornell-box", "veach-mlt", "bca89b21b537a8599343207e30dee7661be023cf9a9afb39d90ea722d285546a"},
    Case{"caustic-mirror", "veach-mlt", "6783afad6e36a0cfce75d50d680fb42ceb1138219ce4af04a59df57301a8937c"},
    Case{"glossy-plates", "veach-mlt", "6f626af7b83493c32c97034f40f4d029c456b52067795f71d14ead86d9e04497"},
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
