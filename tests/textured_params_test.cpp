// Textures wherever Mitsuba takes one: specular_reflectance / specular_transmittance / alpha of the
// BSDFs and the radiance of area lights, loaded from XML and evaluated at the hit's uv. The check that
// "every method sees the same value" is done at the interface every method goes through: a textured
// BSDF (light) queried at a uv inside a texture cell answers exactly what the constant BSDF (light) with
// that cell's value answers, for eval, pdf and sample (sampleLi, sampleLe, L).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "tests/support/temp_dir.h"
#include "common/bsdf/make_bsdf.h"
#include "common/bsdf/texture.h"
#include "common/core/rng.h"
#include "common/emitter/make_light.h"
#include "common/integrators/evaluators.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"
#include "tests/support/estimates.h"

namespace fs = std::filesystem;

namespace mlt {
namespace {

SceneDesc loadBody(const TempDir& d, const std::string& body, const std::string& version = "3.0.0") {
  return loadMitsubaScene(d.write("scene.xml", "<scene version=\"" + version + "\">\n" + body + "</scene>\n"));
}

const BsdfDesc& byId(const SceneDesc& s, const std::string& id) {
  for (const BsdfDesc& b : s.bsdfs)
    if (b.id == id) return b;
  throw std::runtime_error("no bsdf " + id);
}

// ------------------------------------------------------------------------------------------------------
// Loading
// ------------------------------------------------------------------------------------------------------

// Veach's door-ajar floor as published for Mitsuba 0.6 (Bitterli's conversion): a two-sided rough
// conductor whose specularReflectance is a checkerboard with uscale / vscale.
TEST(TexturedParams, DoorAjarFloorLoads06) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <bsdf type="twosided" id="Floor">
    <bsdf type="roughconductor">
      <float name="alpha" value="0.1"/>
      <string name="distribution" value="ggx"/>
      <rgb name="eta" value="1.65746, 0.880369, 0.521229"/>
      <rgb name="k" value="9.22387, 6.26952, 4.837"/>
      <texture name="specularReflectance" type="checkerboard">
        <rgb name="color0" value="0.2"/>
        <rgb name="color1" value="0.4"/>
        <float name="uoffset" value="0"/>
        <float name="voffset" value="0"/>
        <float name="uscale" value="20"/>
        <float name="vscale" value="80"/>
      </texture>
    </bsdf>
  </bsdf>
  <shape type="rectangle"><ref id="Floor"/></shape>
)", "0.6.0");
  const BsdfDesc& floor = s.bsdfs[byId(s, "Floor").nested];
  EXPECT_EQ(floor.type, BsdfDesc::Type::RoughConductor);
  ASSERT_EQ(floor.specularReflectance.type, TextureDesc::Type::Checkerboard);
  EXPECT_FLOAT_EQ(floor.specularReflectance.uvScale.x, 20.0f);
  EXPECT_FLOAT_EQ(floor.specularReflectance.uvScale.y, 80.0f);
  EXPECT_FLOAT_EQ(floor.specularReflectance.color1.r, 0.4f);
  // It builds.
  EXPECT_NE(makeBsdf(s, byId(s, "Floor")), nullptr);
}

TEST(TexturedParams, Mitsuba3NamesRefsAlphaAndRadiance) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <texture type="checkerboard" id="rough">
    <rgb name="color0" value="0.05"/><rgb name="color1" value="0.3"/>
    <transform name="to_uv"><scale x="4" y="2"/></transform>
  </texture>
  <bsdf type="roughdielectric" id="rd"><ref name="alpha" id="rough"/>
    <texture name="specular_transmittance" type="checkerboard"/></bsdf>
  <bsdf type="roughconductor" id="rc"><texture name="alpha" type="checkerboard"/></bsdf>
  <bsdf type="conductor" id="c"><ref name="specular_reflectance" id="rough"/></bsdf>
  <bsdf type="plastic" id="p"><texture name="specular_reflectance" type="checkerboard"/></bsdf>
  <bsdf type="dielectric" id="g"><rgb name="specular_reflectance" value="0.7"/></bsdf>
  <shape type="rectangle"><emitter type="area">
    <texture name="radiance" type="checkerboard"><rgb name="color0" value="3"/><rgb name="color1" value="1"/></texture>
  </emitter></shape>
  <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
)");
  const BsdfDesc& rd = byId(s, "rd");
  ASSERT_TRUE(rd.alphaTexture.has_value());
  EXPECT_FLOAT_EQ(rd.alphaTexture->uvScale.x, 4.0f);
  EXPECT_EQ(rd.specularTransmittance.type, TextureDesc::Type::Checkerboard);
  EXPECT_TRUE(rd.specularReflectance.isConstant());
  EXPECT_TRUE(byId(s, "rc").alphaTexture.has_value());
  EXPECT_EQ(byId(s, "c").specularReflectance.type, TextureDesc::Type::Checkerboard);
  EXPECT_EQ(byId(s, "p").specularReflectance.type, TextureDesc::Type::Checkerboard);
  EXPECT_FLOAT_EQ(byId(s, "g").specularReflectance.value.g, 0.7f);
  ASSERT_EQ(s.meshes.size(), 2u);
  ASSERT_TRUE(s.meshes[0].emissionTexture.has_value());
  EXPECT_FLOAT_EQ(s.meshes[0].emissionTexture->color0.r, 3.0f);
  EXPECT_FALSE(s.meshes[1].emissionTexture.has_value());
  EXPECT_FLOAT_EQ(s.meshes[1].emission->r, 2.0f);
  for (const BsdfDesc& b : s.bsdfs) EXPECT_NE(makeBsdf(s, b), nullptr) << b.id;
}

TEST(TexturedParams, UnsupportedTexturesNameFileLineAndParameter) {
  TempDir d;
  auto expectError = [&](const std::string& body, int line, const std::string& what) {
    try {
      loadBody(d, body);
      ADD_FAILURE() << "no error for " << body;
    } catch (const SceneError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("scene.xml:" + std::to_string(line) + ":"), std::string::npos) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
  };
  expectError("<bsdf type=\"roughplastic\">\n  <texture name=\"alpha\" type=\"checkerboard\"/></bsdf>\n", 3,
              "textured alpha is not supported on roughplastic");
  expectError("<bsdf type=\"roughconductor\">\n  <texture name=\"alpha_u\" type=\"checkerboard\"/></bsdf>\n", 3,
              "alpha_u");
  expectError("<bsdf type=\"conductor\">\n  <texture name=\"specular_reflectance\" type=\"noise\"/></bsdf>\n", 3,
              "unsupported texture type 'noise'");
  expectError("<bsdf type=\"conductor\">\n  <texture name=\"eta\" type=\"checkerboard\"/></bsdf>\n", 3, "eta");
}

// ------------------------------------------------------------------------------------------------------
// Evaluation at the hit's uv
// ------------------------------------------------------------------------------------------------------

// A checkerboard with 2x2 cells per unit uv: (0.1, 0.1) is in a color0 cell, (0.6, 0.1) in a color1 cell.
TextureDesc checker(Color c0, Color c1) {
  TextureDesc t;
  t.type = TextureDesc::Type::Checkerboard;
  t.color0 = c0;
  t.color1 = c1;
  return t;
}
const Vec2 kCell0{0.1f, 0.1f}, kCell1{0.6f, 0.1f};

Vec3 dir(float theta, float phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// textured(uv) must equal constant_c(uv) for every query, bit for bit.
void expectSameBsdf(const Bsdf& textured, Vec2 uv, const Bsdf& constant, const std::string& what) {
  Pcg32 rng(7, 1);
  const BsdfQuery q{uv, TransportMode::Radiance};
  for (int i = 0; i < 64; ++i) {
    const Vec3 wo = dir(1.4f * rng.uniform(), 6.28f * rng.uniform());
    Vec3 wi = dir(1.4f * rng.uniform(), 6.28f * rng.uniform());
    if (i % 3 == 2) wi = -wi;  // transmission side
    const Color a = textured.eval(wo, wi, q), b = constant.eval(wo, wi, q);
    EXPECT_EQ(a.r, b.r) << what;
    EXPECT_EQ(a.g, b.g) << what;
    EXPECT_EQ(textured.pdf(wo, wi, q), constant.pdf(wo, wi, q)) << what;
    const float uc = rng.uniform();
    const Vec2 ud = rng.uniform2();
    const auto sa = textured.sample(wo, uc, ud, q), sb = constant.sample(wo, uc, ud, q);
    ASSERT_EQ(sa.has_value(), sb.has_value()) << what;
    if (sa) {
      EXPECT_EQ(sa->f.r, sb->f.r) << what;
      EXPECT_EQ(sa->f.b, sb->f.b) << what;
      EXPECT_EQ(sa->pdfW, sb->pdfW) << what;
      EXPECT_EQ(sa->wi.x, sb->wi.x) << what;
    }
  }
  const Color aa = textured.albedo(uv), ab = constant.albedo(uv);
  EXPECT_EQ(aa.r, ab.r) << what;
}

TEST(TexturedParams, TexturedBsdfsAnswerLikeTheConstantOfTheirCell) {
  using T = BsdfDesc::Type;
  const Color c0(0.2f, 0.5f, 0.9f), c1(0.8f, 0.3f, 0.1f);
  struct Case {
    T type;
    bool transmittance;
  };
  for (const Case c : {Case{T::Conductor, false}, Case{T::RoughConductor, false}, Case{T::Dielectric, false},
                       Case{T::Dielectric, true}, Case{T::ThinDielectric, true}, Case{T::RoughDielectric, false},
                       Case{T::RoughDielectric, true}}) {
    // (Plastics choose their lobe by the texture's mean, so a constant with one cell's value samples
    // differently; they have their own test below.)
    BsdfDesc tex;
    tex.type = c.type;
    tex.id = "textured";
    tex.eta = Color(0.2f, 0.9f, 1.1f);
    tex.k = Color(3.9f, 2.4f, 2.2f);
    tex.alpha = 0.3f;
    (c.transmittance ? tex.specularTransmittance : tex.specularReflectance) = checker(c0, c1);
    BsdfDesc k0 = tex, k1 = tex;
    (c.transmittance ? k0.specularTransmittance : k0.specularReflectance) = c0;
    (c.transmittance ? k1.specularTransmittance : k1.specularReflectance) = c1;
    const auto t = makeBsdf({}, tex);
    const std::string what = "type " + std::to_string(int(c.type)) + (c.transmittance ? " transmittance" : "");
    expectSameBsdf(*t, kCell0, *makeBsdf({}, k0), what + " cell 0");
    expectSameBsdf(*t, kCell1, *makeBsdf({}, k1), what + " cell 1");
  }
}

TEST(TexturedParams, TexturedPlasticSpecularFollowsTheCell) {
  // Plastic's lobe choice uses the texture's average (Mitsuba: specular_reflectance->mean()); give the
  // constants the same weight by comparing f / specular value of each cell directly.
  BsdfDesc tex;
  tex.type = BsdfDesc::Type::Plastic;
  tex.id = "plastic";
  tex.specularReflectance = checker(Color(0.25f), Color(1.0f));
  const auto t = makeBsdf({}, tex);
  const Vec3 wo = dir(0.4f, 0.0f);
  const auto s0 = t->sample(wo, 0.0f, {0.5f, 0.5f}, {kCell0, TransportMode::Radiance});
  const auto s1 = t->sample(wo, 0.0f, {0.5f, 0.5f}, {kCell1, TransportMode::Radiance});
  ASSERT_TRUE(s0 && s1);
  ASSERT_TRUE(s0->delta && s1->delta);
  EXPECT_FLOAT_EQ(s1->f.r, 4 * s0->f.r);
  EXPECT_EQ(s0->pdfW, s1->pdfW);

  // Rough plastic with a black base: eval is the specular lobe alone, scaled by the cell's value.
  tex.type = BsdfDesc::Type::RoughPlastic;
  tex.reflectance = Color(0.0f);
  tex.alpha = 0.2f;
  const auto r = makeBsdf({}, tex);
  const Vec3 wi = dir(0.5f, 3.0f);
  const BsdfQuery q0{kCell0, TransportMode::Radiance}, q1{kCell1, TransportMode::Radiance};
  EXPECT_GT(r->eval(wo, wi, q0).r, 0.0f);
  EXPECT_FLOAT_EQ(r->eval(wo, wi, q1).r, 4 * r->eval(wo, wi, q0).r);
  EXPECT_EQ(r->pdf(wo, wi, q0), r->pdf(wo, wi, q1));
}

TEST(TexturedParams, TexturedAlphaAnswersLikeTheConstantAlphaOfTheCell) {
  for (BsdfDesc::Type type : {BsdfDesc::Type::RoughConductor, BsdfDesc::Type::RoughDielectric}) {
    BsdfDesc tex;
    tex.type = type;
    tex.id = "rough";
    tex.distribution = MicrofacetType::GGX;
    tex.eta = Color(0.2f);
    tex.k = Color(3.0f);
    tex.alphaTexture = checker(Color(0.05f), Color(0.4f));
    BsdfDesc k0 = tex, k1 = tex;
    k0.alphaTexture.reset();
    k1.alphaTexture.reset();
    k0.alpha = luminance(Color(0.05f));
    k1.alpha = luminance(Color(0.4f));
    const auto t = makeBsdf({}, tex);
    expectSameBsdf(*t, kCell0, *makeBsdf({}, k0), "alpha cell 0");
    expectSameBsdf(*t, kCell1, *makeBsdf({}, k1), "alpha cell 1");
  }
}

// A unit quad [0,1]^2 at z = 0 facing +z with uv = (x, y); a checkerboard radiance.
MeshDesc quadLight(bool withUvs) {
  MeshDesc m;
  m.name = "quad light";
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  if (withUvs) m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.indices = {0, 1, 2, 0, 2, 3};
  m.emission = Color(1.0f);
  m.emissionTexture = checker(Color(3.0f), Color(1.0f));
  return m;
}

TEST(TexturedParams, TexturedAreaLightEvaluatesAtThePointsUv) {
  const MeshDesc m = quadLight(true);
  const auto light = makeAreaLight(m);
  // L at a hit's uv.
  EXPECT_FLOAT_EQ(light->L({0.1f, 0.1f, 0}, {0, 0, 1}, kCell0, {0, 0, 1}).r, 3.0f);
  EXPECT_FLOAT_EQ(light->L({0.6f, 0.1f, 0}, {0, 0, 1}, kCell1, {0, 0, 1}).r, 1.0f);
  EXPECT_FLOAT_EQ(light->L({0.6f, 0.1f, 0}, {0, 0, 1}, kCell1, {0, 0, -1}).r, 0.0f);  // back side
  // Power: the average radiance (2) times pi A.
  EXPECT_NEAR(light->power().r, 2.0f * 3.14159265f, 1e-5);
  // Sampled points carry the texture's value at their own uv (= their xy here).
  const CheckerboardTexture ref(Color(3.0f), Color(1.0f), {1, 1}, {0, 0});
  Pcg32 rng(3, 1);
  for (int i = 0; i < 200; ++i) {
    const auto li = light->sampleLi({0.3f, 0.4f, 2.0f}, rng.uniform2());
    ASSERT_TRUE(li.has_value());
    EXPECT_EQ(li->L.r, ref.eval({li->pLight.x, li->pLight.y}).r);
    const auto le = light->sampleLe(rng.uniform2(), rng.uniform2());
    ASSERT_TRUE(le.has_value());
    EXPECT_EQ(le->L.r, ref.eval({le->ray.o.x, le->ray.o.y}).r);
    // The sample carries its uv, so L() at the sampled point (bdpt's s = 1 vertex) agrees.
    EXPECT_EQ(light->L(le->ray.o, le->nLight, le->uv, le->ray.d).r, le->L.r);
    EXPECT_EQ(light->L(li->pLight, li->nLight, li->uv, -li->wi).r, li->L.r);
  }
}

TEST(TexturedParams, TexturedAreaLightWithoutUvsUsesBarycentrics) {
  // Without mesh uvs a hit's uv is Embree's barycentric (u, v) of its triangle: weight of vertex 1 and 2.
  const MeshDesc m = quadLight(false);
  const auto light = makeAreaLight(m);
  const CheckerboardTexture ref(Color(3.0f), Color(1.0f), {1, 1}, {0, 0});
  Pcg32 rng(5, 1);
  for (int i = 0; i < 200; ++i) {
    const auto le = light->sampleLe(rng.uniform2(), rng.uniform2());
    ASSERT_TRUE(le.has_value());
    const Vec3 p = le->ray.o;
    // Triangle (0,1,2) covers x >= y: p = v0 + u (v1 - v0) + v (v2 - v0) -> v = y, u = x - y.
    // Triangle (0,2,3) covers y >  x: u = x, v = y - x.
    const Vec2 uv = p.x >= p.y ? Vec2(p.x - p.y, p.y) : Vec2(p.x, p.y - p.x);
    const float expect = ref.eval(uv).r;
    // Points on the diagonal may belong to either triangle; skip them.
    if (std::fabs(p.x - p.y) < 1e-4f) continue;
    EXPECT_EQ(le->L.r, expect) << p.x << " " << p.y;
  }
}

// Every technique sees the same textured values: a checkerboard light seen directly (pt: L() at the hit;
// lt: the (1, 1) strategy, L() at the sampled point) over a floor with a bitmap-free checkerboard
// reflectance and a rough metal ball with textured specular reflectance and alpha. pt, lt and bdpt agree
// on the image mean and 3 x 3 tile means within 5 standard errors.
TEST(TexturedParams, PtLtAndBdptAgreeOnTexturedScene) {
  TempDir d;
  const SceneDesc desc = loadBody(d, R"(
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="50"/>
    <transform name="to_world"><lookat origin="0, 0.6, 3" target="0, 0.4, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="18"/><integer name="height" value="18"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><texture name="reflectance" type="checkerboard"><rgb name="color0" value="0.8"/>
      <rgb name="color1" value="0.2, 0.3, 0.5"/><transform name="to_uv"><scale x="3" y="3"/></transform></texture></bsdf></shape>
  <shape type="sphere"><point name="center" x="0.5" y="0.3" z="0.3"/><float name="radius" value="0.3"/>
    <bsdf type="roughconductor"><string name="distribution" value="ggx"/>
      <texture name="specular_reflectance" type="checkerboard"><rgb name="color0" value="0.9, 0.7, 0.3"/><rgb name="color1" value="0.5"/>
        <transform name="to_uv"><scale x="6" y="3"/></transform></texture>
      <texture name="alpha" type="checkerboard"><rgb name="color0" value="0.05"/><rgb name="color1" value="0.4"/>
        <transform name="to_uv"><scale x="4" y="2"/></transform></texture></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="0.6" y="0.4"/><translate y="0.7" z="-0.8"/></transform>
    <bsdf type="diffuse"/>
    <emitter type="area"><texture name="radiance" type="checkerboard"><rgb name="color0" value="8, 6, 4"/>
      <rgb name="color1" value="1, 1, 2"/><transform name="to_uv"><scale x="2" y="1"/></transform></texture></emitter></shape>
)");
  const auto scene = RenderScene::build(desc);
  IntegratorSettings is;
  is.maxDepth = 4;
  is.rrDepth = 5;
  auto run = [&](const char* m, uint64_t seed, uint64_t n) {
    const auto ev = makeEvaluator(*scene, m, is);
    return test::estimateImage(*ev, 18, 18, seed, n, 3, 3);
  };
  const test::ImageStats bd = run("bdpt", 1, 18 * 18 * 300);
  for (const auto& [m, n] : {std::pair<const char*, uint64_t>{"pt", 18 * 18 * 600}, {"lt", 18 * 18 * 1200}}) {
    const test::ImageStats st = run(m, 2, n);
    int where = -1;
    const double z = test::maxZ(st, bd, &where);
    std::printf("%s vs bdpt: %.5f +- %.5f vs %.5f +- %.5f, max z %.2f\n", m, st.mean[0], st.stdErr[0], bd.mean[0],
                bd.stdErr[0], z);
    EXPECT_LT(z, 5.0) << m << " entry " << where << ": " << st.mean[where] << " vs " << bd.mean[where];
    EXPECT_LT(5 * std::hypot(st.stdErr[0], bd.stdErr[0]), 0.05 * bd.mean[0]) << m;  // it can fail
  }
}

}  // namespace
}  // namespace mlt
