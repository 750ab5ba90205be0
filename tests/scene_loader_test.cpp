// Mitsuba XML front end, mesh readers, SHA-256 and scene hashing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "tests/support/temp_dir.h"
#include "common/core/rng.h"
#include "common/core/sha256.h"
#include "common/scene/mesh_readers.h"
#include "common/scene/mitsuba_loader.h"
#include "common/scene/scene_hash.h"
#include "common/scene/scene_loader.h"
#include "common/scene/xml_parser.h"

namespace fs = std::filesystem;

namespace mlt {
namespace {

const std::string kData = std::string(MLTFARM_SOURCE_DIR) + "/tests/data/scenes";
const std::string kScenes = std::string(MLTFARM_SOURCE_DIR) + "/scenes";


// Line 1 is <scene ...>, so the body starts on line 2.
std::string sceneXml(const std::string& body, const std::string& version = "3.0.0") {
  return "<scene version=\"" + version + "\">\n" + body + "</scene>\n";
}

SceneDesc loadBody(const TempDir& d, const std::string& body, const std::string& version = "3.0.0",
                   const std::map<std::string, std::string>& defines = {}) {
  return loadMitsubaScene(d.write("scene.xml", sceneXml(body, version)), defines);
}

// Loads and expects a SceneError whose message names `file` and `line` and contains `what`.
void expectError(const TempDir& d, const std::string& xmlFileContent, int line, const std::string& what,
                 const std::string& fileName = "scene.xml") {
  const std::string path = d.write(fileName, xmlFileContent);
  try {
    loadMitsubaScene(path);
    ADD_FAILURE() << "no error for:\n" << xmlFileContent;
  } catch (const SceneError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(fileName + ":" + std::to_string(line) + ":"), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
}

Vec3 triNormal(const MeshDesc& m, size_t t) {
  const Vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]], c = m.positions[m.indices[3 * t + 2]];
  return normalize(cross(b - a, c - a));
}
Vec3 triCentroid(const MeshDesc& m, size_t t) {
  return (m.positions[m.indices[3 * t]] + m.positions[m.indices[3 * t + 1]] + m.positions[m.indices[3 * t + 2]]) / 3.0f;
}
double meshArea(const MeshDesc& m) {
  double a = 0;
  for (size_t t = 0; t < m.indices.size() / 3; ++t) {
    const Vec3 p0 = m.positions[m.indices[3 * t]], p1 = m.positions[m.indices[3 * t + 1]], p2 = m.positions[m.indices[3 * t + 2]];
    a += 0.5 * length(cross(p1 - p0, p2 - p0));
  }
  return a;
}
void expectVec(const Vec3& a, const Vec3& b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}
void expectColor(const Color& a, const Color& b, float tol = 1e-6f) {
  EXPECT_NEAR(a.r, b.r, tol);
  EXPECT_NEAR(a.g, b.g, tol);
  EXPECT_NEAR(a.b, b.b, tol);
}

// ------------------------------------------------------------------------------------------------------
// SHA-256: FIPS 180-2 appendix B vectors
// ------------------------------------------------------------------------------------------------------

TEST(Sha256, FipsVectors) {
  EXPECT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256Hex(std::string(1000000, 'a')), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  // 896-bit message (FIPS 180-4 example).
  EXPECT_EQ(sha256Hex("abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmnoijklmnopjklmnopqklmnopqrlmnopqrs"
                      "mnopqrstnopqrstu"),
            "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1");
}

TEST(Sha256, IncrementalEqualsOneShot) {
  std::string data;
  for (int i = 0; i < 1000; ++i) data += char(i * 7 + 3);
  for (size_t split : {0, 1, 55, 56, 63, 64, 65, 999}) {
    Sha256 h;
    h.update(data.data(), split);
    h.update(data.data() + split, data.size() - split);
    EXPECT_EQ(h.hexDigest(), sha256Hex(data)) << split;
  }
}

// ------------------------------------------------------------------------------------------------------
// XML parser
// ------------------------------------------------------------------------------------------------------

TEST(XmlParser, ElementsAttributesEntitiesAndLines) {
  const std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<!-- a comment\n spanning lines -->\n"
      "<root a='1' b=\"x &lt;&amp;&gt; &quot;&apos; &#65;&#x42;\">\n"
      "  <child name=\"c\"/>\n"
      "  <!-- <notachild/> -->\n"
      "  <other>text</other>\n"
      "</root>\n";
  const XmlElement root = parseXmlString(text, "t.xml");
  EXPECT_EQ(root.name, "root");
  EXPECT_EQ(root.line, 4);
  ASSERT_EQ(root.children.size(), 2u);
  EXPECT_EQ(root.find("b")->value, "x <&> \"' AB");
  EXPECT_EQ(root.find("a")->value, "1");
  EXPECT_EQ(root.children[0].line, 5);
  EXPECT_EQ(root.children[1].name, "other");
  EXPECT_EQ(root.children[1].line, 7);
  EXPECT_EQ(root.children[1].text, "text");
}

TEST(XmlParser, BrokenXmlNamesFileAndLine) {
  auto expectFail = [](const std::string& text, int line, const std::string& what) {
    try {
      parseXmlString(text, "bad.xml");
      ADD_FAILURE() << "no error for " << text;
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.xml:" + std::to_string(line) + ":"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      EXPECT_EQ(e.line(), line);
    }
  };
  expectFail("<a>\n<b>\n</c>\n</a>", 3, "does not match <b>");
  expectFail("<a>\n<!-- never closed\n", 2, "unterminated comment");
  expectFail("<a x=\"1\"\n x=\"2\"/>", 2, "duplicate attribute");
  expectFail("<a>\n<b/>\n", 1, "never closed");
  expectFail("<a/>\n<b/>", 2, "after the root element");
  expectFail("<a x=1/>", 1, "quoted value");
  expectFail("<a>\n&bogus;</a>", 2, "unknown entity");
  expectFail("", 1, "no root element");
}

// ------------------------------------------------------------------------------------------------------
// Sensor, film, integrator
// ------------------------------------------------------------------------------------------------------

TEST(MitsubaLoader, SensorLookatFilmSamplerIntegrator) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <integrator type="path"><integer name="max_depth" value="7"/><integer name="rr_depth" value="3"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="19.5"/>
    <string name="fov_axis" value="y"/>
    <float name="near_clip" value="0.1"/>
    <float name="far_clip" value="100"/>
    <transform name="to_world"><lookat origin="0, 1, 6.8" target="0, 1, 2.7" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm">
      <integer name="width" value="320"/><integer name="height" value="200"/>
      <string name="pixel_format" value="rgb"/>
      <rfilter type="box"/>
    </film>
  </sensor>
)");
  EXPECT_EQ(s.camera.type, CameraDesc::Type::Perspective);
  EXPECT_FLOAT_EQ(s.camera.fovDeg, 19.5f);
  EXPECT_EQ(s.camera.fovAxis, CameraDesc::FovAxis::Y);
  EXPECT_FLOAT_EQ(s.camera.nearClip, 0.1f);
  EXPECT_EQ(s.camera.width, 320);
  EXPECT_EQ(s.camera.height, 200);
  EXPECT_EQ(s.sampleCount, 16);
  EXPECT_EQ(s.maxDepth, 7);
  EXPECT_EQ(s.rrDepth, 3);
  EXPECT_TRUE(s.warnings.empty());
  // Mitsuba lookat: columns are left = up x dir, up, dir, origin. dir = -z, so left = -x.
  const double expected[4][4] = {{-1, 0, 0, 0}, {0, 1, 0, 1}, {0, 0, -1, 6.8}, {0, 0, 0, 1}};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(s.camera.toWorld.m[i][j], expected[i][j], 1e-6) << i << "," << j;
}

TEST(MitsubaLoader, Mitsuba06Spellings) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <integrator type="volpath"><integer name="maxDepth" value="9"/><integer name="rrDepth" value="4"/></integrator>
  <sensor type="thinlens">
    <float name="fov" value="30"/>
    <string name="fovAxis" value="diagonal"/>
    <float name="nearClip" value="0.5"/>
    <float name="apertureRadius" value="0.2"/>
    <float name="focusDistance" value="3"/>
    <transform name="toWorld"><translate x="1"/></transform>
    <sampler type="ldsampler"><integer name="sampleCount" value="8"/></sampler>
    <film type="hdrfilm"><integer name="width" value="10"/><integer name="height" value="20"/>
      <boolean name="banner" value="false"/><boolean name="highQualityEdges" value="true"/></film>
  </sensor>
  <bsdf type="dielectric" id="glass"><float name="intIOR" value="1.33"/><string name="extIOR" value="vacuum"/></bsdf>
  <bsdf type="conductor" id="cu"/>
  <bsdf type="roughplastic" id="rp">
    <rgb name="diffuseReflectance" value="0.1, 0.2, 0.3"/><rgb name="specularReflectance" value="0.9"/>
    <float name="alphaU" value="0.3"/><float name="alphaV" value="0.3"/><boolean name="nonlinear" value="true"/>
  </bsdf>
  <shape type="rectangle">
    <transform name="toWorld"><scale value="2"/></transform>
    <boolean name="flipNormals" value="true"/>
    <ref id="glass"/>
  </shape>
  <emitter type="spot">
    <rgb name="intensity" value="5"/>
    <float name="cutoffAngle" value="30"/><float name="beamWidth" value="10"/>
    <transform name="toWorld"><lookat origin="0, 5, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
    <float name="samplingWeight" value="2"/>
  </emitter>
)",
                               "0.6.0");
  EXPECT_EQ(s.maxDepth, 9);
  EXPECT_EQ(s.rrDepth, 4);
  EXPECT_EQ(s.camera.type, CameraDesc::Type::ThinLens);
  EXPECT_EQ(s.camera.fovAxis, CameraDesc::FovAxis::Diagonal);
  EXPECT_FLOAT_EQ(s.camera.apertureRadius, 0.2f);
  EXPECT_FLOAT_EQ(s.camera.focusDistance, 3.0f);
  EXPECT_FLOAT_EQ(s.camera.nearClip, 0.5f);
  EXPECT_DOUBLE_EQ(s.camera.toWorld.m[0][3], 1.0);
  EXPECT_EQ(s.sampleCount, 8);
  ASSERT_EQ(s.bsdfs.size(), 3u);
  EXPECT_EQ(s.bsdfs[0].type, BsdfDesc::Type::Dielectric);
  EXPECT_FLOAT_EQ(s.bsdfs[0].intIOR, 1.33f);
  EXPECT_FLOAT_EQ(s.bsdfs[0].extIOR, 1.0f);
  // 0.6 conductors default to copper with eta relative to air.
  EXPECT_EQ(s.bsdfs[1].type, BsdfDesc::Type::Conductor);
  EXPECT_FALSE(s.bsdfs[1].mirror);
  EXPECT_NEAR(s.bsdfs[1].eta.r, 0.2004f, 1e-3f);
  EXPECT_NEAR(s.bsdfs[1].k.r, 3.9129f, 1e-3f);
  EXPECT_FLOAT_EQ(s.bsdfs[1].extIOR, 1.000277f);
  EXPECT_EQ(s.bsdfs[2].type, BsdfDesc::Type::RoughPlastic);
  expectColor(s.bsdfs[2].reflectance.value, {0.1f, 0.2f, 0.3f});
  expectColor(s.bsdfs[2].specularReflectance.value, Color(0.9f));
  EXPECT_FLOAT_EQ(s.bsdfs[2].alpha, 0.3f);
  EXPECT_TRUE(s.bsdfs[2].nonlinear);
  EXPECT_EQ(s.bsdfs[2].distribution, MicrofacetType::Beckmann);
  EXPECT_FLOAT_EQ(s.bsdfs[2].intIOR, 1.49f);  // polypropylene
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.meshes[0].bsdf, 0);
  for (size_t t = 0; t < 2; ++t) expectVec(triNormal(s.meshes[0], t), {0, 0, -1});  // flipped
  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_EQ(s.lights[0].type, LightDesc::Type::Spot);
  EXPECT_FLOAT_EQ(s.lights[0].cutoffAngleDeg, 30.0f);
  EXPECT_FLOAT_EQ(s.lights[0].beamWidthDeg, 10.0f);
  expectVec(s.lights[0].position, {0, 5, 0});
  expectVec(s.lights[0].direction, {0, -1, 0});
  expectColor(s.lights[0].intensity, Color(5.0f));
}

TEST(MitsubaLoader, FocalLengthDefaultsAndFilterFallback) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <sensor type="perspective">
    <string name="focal_length" value="35mm"/>
    <film type="ldrfilm"><rfilter type="gaussian"><float name="stddev" value="0.5"/></rfilter></film>
  </sensor>
)");
  EXPECT_EQ(s.camera.fovAxis, CameraDesc::FovAxis::Diagonal);
  EXPECT_NEAR(s.camera.fovDeg, 2 * std::atan(std::sqrt(36.0 * 36 + 24 * 24) / 70.0) * 180 / M_PI, 1e-4);
  EXPECT_EQ(s.camera.width, 768);  // Mitsuba's film defaults
  EXPECT_EQ(s.camera.height, 576);
  ASSERT_EQ(s.warnings.size(), 2u);  // ldrfilm and gaussian -> box
  EXPECT_NE(s.warnings[1].find("gaussian"), std::string::npos);
  EXPECT_NE(s.warnings[1].find("scene.xml:5:"), std::string::npos) << s.warnings[1];
}

// ------------------------------------------------------------------------------------------------------
// Transforms
// ------------------------------------------------------------------------------------------------------

TEST(MitsubaLoader, TransformsComposeInDocumentOrder) {
  TempDir d;
  // translate(1,2,3), then rotate 90 deg about z, then scale 2: M = S R T. By hand: p -> 2 R (p + t),
  // R(x, y, z) = (-y, x, z), so the linear part is 2R and the translation 2 R t = (-4, 2, 6).
  const SceneDesc s = loadBody(d, R"(
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world">
      <translate x="1" y="2" z="3"/>
      <rotate z="1" angle="90"/>
      <scale value="2"/>
    </transform>
  </sensor>
)");
  const double expected[4][4] = {{0, -2, 0, -4}, {2, 0, 0, 2}, {0, 0, 2, 6}, {0, 0, 0, 1}};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(s.camera.toWorld.m[i][j], expected[i][j], 1e-12) << i << "," << j;

  // 3.x forms: translate value, rotate value axis, per-axis scale, and an explicit matrix after them (the
  // scale uniform: a sensor's to_world must be a similarity).
  const SceneDesc s2 = loadBody(d, R"(
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world">
      <translate value="1, 0, 0"/>
      <rotate value="0, 1, 0" angle="180"/>
      <scale x="3" y="3" z="3"/>
      <matrix value="1 0 0 10  0 1 0 20  0 0 1 30  0 0 0 1"/>
    </transform>
  </sensor>
)");
  // p=(0,0,0): +(1,0,0) -> rot y 180 -> (-1,0,0) -> scale -> (-3,0,0) -> +(10,20,30) = (7,20,30).
  expectVec(s2.camera.toWorld.point({0, 0, 0}), {7, 20, 30});
  // p=(0,1,1): (1,1,1) -> (-1,1,-1) -> (-3,3,-3) -> (7,23,27).
  expectVec(s2.camera.toWorld.point({0, 1, 1}), {7, 23, 27});
}

// ------------------------------------------------------------------------------------------------------
// Shapes
// ------------------------------------------------------------------------------------------------------

TEST(MitsubaLoader, AnalyticShapesGeometry) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <bsdf type="diffuse" id="w"/>
  <shape type="rectangle"><ref id="w"/></shape>
  <shape type="cube"><ref id="w"/></shape>
  <shape type="sphere"><point name="center" x="1" y="2" z="3"/><float name="radius" value="0.5"/><ref id="w"/></shape>
  <shape type="disk"><ref id="w"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale x="-1"/></transform><ref id="w"/></shape>
  <shape type="sphere"><boolean name="flip_normals" value="true"/><ref id="w"/></shape>
)");
  ASSERT_EQ(s.meshes.size(), 6u);
  const MeshDesc& rect = s.meshes[0];
  EXPECT_EQ(rect.indices.size(), 6u);
  EXPECT_NEAR(meshArea(rect), 4.0, 1e-6);
  for (const Vec3& p : rect.positions) {
    EXPECT_EQ(std::fabs(p.x), 1.0f);
    EXPECT_EQ(std::fabs(p.y), 1.0f);
    EXPECT_EQ(p.z, 0.0f);
  }
  for (size_t t = 0; t < 2; ++t) expectVec(triNormal(rect, t), {0, 0, 1});

  const MeshDesc& cube = s.meshes[1];
  EXPECT_EQ(cube.indices.size(), 36u);
  EXPECT_NEAR(meshArea(cube), 24.0, 1e-5);
  for (size_t t = 0; t < 12; ++t) EXPECT_GT(dot(triNormal(cube, t), triCentroid(cube, t)), 0.99f);  // outward

  const MeshDesc& sph = s.meshes[2];
  const Vec3 c(1, 2, 3);
  for (const Vec3& p : sph.positions) EXPECT_NEAR(length(p - c), 0.5f, 1e-5f);
  EXPECT_NEAR(meshArea(sph), 4 * M_PI * 0.25, 4 * M_PI * 0.25 * 2e-3);
  ASSERT_EQ(sph.normals.size(), sph.positions.size());
  for (size_t i = 0; i < sph.positions.size(); ++i) expectVec(sph.normals[i], normalize(sph.positions[i] - c), 1e-4f);
  for (size_t t = 0; t < sph.indices.size() / 3; ++t) EXPECT_GT(dot(triNormal(sph, t), triCentroid(sph, t) - c), 0.0f);

  const MeshDesc& disk = s.meshes[3];
  EXPECT_NEAR(meshArea(disk), M_PI, M_PI * 1e-3);
  for (size_t t = 0; t < disk.indices.size() / 3; ++t) expectVec(triNormal(disk, t), {0, 0, 1});

  // A mirroring transform keeps an analytic shape's normal (the transformed normal, as in Mitsuba).
  for (size_t t = 0; t < 2; ++t) expectVec(triNormal(s.meshes[4], t), {0, 0, 1});

  const MeshDesc& inside = s.meshes[5];
  for (size_t t = 0; t < inside.indices.size() / 3; ++t) EXPECT_LT(dot(triNormal(inside, t), triCentroid(inside, t)), 0.0f);
  for (size_t i = 0; i < inside.positions.size(); ++i) EXPECT_LT(dot(inside.normals[i], inside.positions[i]), 0.0f);
}

TEST(MitsubaLoader, SphereToWorldScalesAfterCenterAndRadius) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <shape type="sphere"><point name="center" value="1, 0, 0"/><float name="radius" value="2"/>
    <transform name="to_world"><translate y="5"/></transform>
    <boolean name="face_normals" value="true"/>
  </shape>
)");
  ASSERT_EQ(s.meshes.size(), 1u);
  for (const Vec3& p : s.meshes[0].positions) EXPECT_NEAR(length(p - Vec3(1, 5, 0)), 2.0f, 1e-5f);
  EXPECT_TRUE(s.meshes[0].normals.empty());
  // No bsdf: Mitsuba's default diffuse 0.5, with a warning naming the line.
  ASSERT_EQ(s.warnings.size(), 2u);  // no sensor, no bsdf
  EXPECT_NE(s.warnings[0].find("scene.xml:3:"), std::string::npos) << s.warnings[0];
  EXPECT_NE(s.warnings[0].find("no bsdf"), std::string::npos) << s.warnings[0];
  EXPECT_EQ(s.bsdfs.at(s.meshes[0].bsdf).type, BsdfDesc::Type::Diffuse);
  expectColor(s.bsdfs.at(s.meshes[0].bsdf).reflectance.value, Color(0.5f));
}

TEST(MeshReaders, ObjTriangulatesAndKeepsNormalsUvs) {
  const MeshDesc m = readObj(kData + "/quad.obj");
  EXPECT_EQ(m.indices.size(), 6u);
  EXPECT_EQ(m.positions.size(), 4u);
  ASSERT_EQ(m.normals.size(), 4u);
  ASSERT_EQ(m.uvs.size(), 4u);
  EXPECT_NEAR(meshArea(m), 1.0, 1e-6);
  for (size_t t = 0; t < 2; ++t) expectVec(triNormal(m, t), {0, 0, 1});
  // Mitsuba flips v for OBJ files: vertex (0,0,0) has vt (0,0) -> uv (0,1).
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_FLOAT_EQ(m.uvs[i].x, m.positions[i].x);
    EXPECT_FLOAT_EQ(m.uvs[i].y, 1.0f - m.positions[i].y);
  }
  const MeshDesc raw = readObj(kData + "/quad.obj", false);
  for (size_t i = 0; i < 4; ++i) EXPECT_FLOAT_EQ(raw.uvs[i].y, raw.positions[i].y);
}

TEST(MeshReaders, PlyAscii) {
  const MeshDesc m = readPly(kData + "/quad.ply");
  EXPECT_EQ(m.positions.size(), 5u);
  EXPECT_EQ(m.normals.size(), 5u);
  ASSERT_EQ(m.uvs.size(), 5u);
  ASSERT_EQ(m.indices.size(), 9u);  // quad -> 2 triangles, + 1 triangle
  EXPECT_EQ(std::vector<uint32_t>(m.indices.begin(), m.indices.begin() + 6), (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_FLOAT_EQ(m.uvs[4].x, 0.5f);
  for (size_t t = 0; t < 3; ++t) expectVec(triNormal(m, t), {0, 0, 1});
}

// A binary PLY with mixed property types, an extra list property and an extra element to skip.
std::string binaryPly(bool bigEndian) {
  std::string h = std::string("ply\nformat ") + (bigEndian ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex 4\nproperty double x\nproperty float y\nproperty float z\n"
                  "property uchar red\nproperty float s\nproperty float t\n"
                  "element face 1\nproperty int flags\nproperty list uchar uint vertex_index\n"
                  "element extra 1\nproperty list ushort short junk\nend_header\n";
  std::string body;
  auto put = [&](const void* p, size_t n) {
    std::string b(static_cast<const char*>(p), n);
    const uint16_t probe = 1;
    const bool hostBig = *reinterpret_cast<const uint8_t*>(&probe) == 0;
    if (hostBig != bigEndian) std::reverse(b.begin(), b.end());
    body += b;
  };
  const float xy[4][2] = {{0, 0}, {2, 0}, {2, 1}, {0, 1}};
  for (int i = 0; i < 4; ++i) {
    const double x = xy[i][0];
    const float y = xy[i][1], z = 0.5f, s = float(i), t = float(10 * i);
    const uint8_t red = 200;
    put(&x, 8); put(&y, 4); put(&z, 4); put(&red, 1); put(&s, 4); put(&t, 4);
  }
  const int32_t flags = 7;
  const uint8_t n = 4;
  put(&flags, 4);
  put(&n, 1);
  for (uint32_t i : {0u, 1u, 2u, 3u}) put(&i, 4);
  const uint16_t cnt = 2;
  const int16_t junk[2] = {-1, 5};
  put(&cnt, 2); put(&junk[0], 2); put(&junk[1], 2);
  return h + body;
}

TEST(MeshReaders, PlyBinaryBothEndians) {
  TempDir d;
  for (bool big : {false, true}) {
    const MeshDesc m = readPly(d.write(big ? "be.ply" : "le.ply", binaryPly(big)));
    ASSERT_EQ(m.positions.size(), 4u) << big;
    EXPECT_TRUE(m.normals.empty());
    ASSERT_EQ(m.uvs.size(), 4u);
    EXPECT_EQ(m.indices.size(), 6u);
    EXPECT_NEAR(meshArea(m), 2.0, 1e-6);
    expectVec(m.positions[2], {2, 1, 0.5f});
    EXPECT_FLOAT_EQ(m.uvs[3].x, 3.0f);
    EXPECT_FLOAT_EQ(m.uvs[3].y, 30.0f);
  }
  // Truncated binary data is an error naming the file.
  const std::string full = binaryPly(false);
  const std::string p = d.write("cut.ply", full.substr(0, full.size() - 7));
  try {
    readPly(p);
    ADD_FAILURE();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.ply"), std::string::npos);
  }
}

TEST(MitsubaLoader, MeshShapesTransformsAndNormalOptions) {
  TempDir d;
  fs::create_directories(d.path() / "meshes");
  fs::copy_file(kData + "/quad.obj", d.path() / "meshes/quad.obj", fs::copy_options::overwrite_existing);
  fs::copy_file(kData + "/quad.ply", d.path() / "quad.ply", fs::copy_options::overwrite_existing);
  d.write("bin.ply", binaryPly(true));
  const SceneDesc s = loadBody(d, R"(
  <shape type="obj"><string name="filename" value="meshes/quad.obj"/>
    <transform name="to_world"><rotate x="1" angle="90"/><translate z="1"/></transform></shape>
  <shape type="ply"><string name="filename" value="quad.ply"/><boolean name="face_normals" value="true"/></shape>
  <shape type="ply"><string name="filename" value="quad.ply"/><boolean name="flip_normals" value="true"/></shape>
  <shape type="ply"><string name="filename" value="bin.ply"/></shape>
  <shape type="obj"><string name="filename" value="meshes/quad.obj"/>
    <transform name="to_world"><scale x="-1"/></transform></shape>
)");
  ASSERT_EQ(s.meshes.size(), 5u);
  // rotate +90 about x maps +z to -y; the normal follows.
  const MeshDesc& obj = s.meshes[0];
  for (const Vec3& n : obj.normals) expectVec(n, {0, -1, 0});
  for (size_t t = 0; t < 2; ++t) expectVec(triNormal(obj, t), {0, -1, 0});
  for (const Vec3& p : obj.positions) EXPECT_NEAR(p.z, 1.0f + p.z - 1.0f, 0);
  EXPECT_TRUE(s.meshes[1].normals.empty());
  for (const Vec3& n : s.meshes[2].normals) expectVec(n, {0, 0, -1});
  for (size_t t = 0; t < 3; ++t) expectVec(triNormal(s.meshes[2], t), {0, 0, -1});
  // No normals in the file and no face_normals: smooth normals are computed (planar here -> +z).
  ASSERT_EQ(s.meshes[3].normals.size(), 4u);
  for (const Vec3& n : s.meshes[3].normals) expectVec(n, {0, 0, 1});
  // A mirrored mesh keeps world-space winding (Mitsuba's meshes): geometric normal flips, vertex normal
  // (inverse transpose) does not.
  for (size_t t = 0; t < 2; ++t) expectVec(triNormal(s.meshes[4], t), {0, 0, -1});
  for (const Vec3& n : s.meshes[4].normals) expectVec(n, {0, 0, 1});
  // Every mesh file is recorded.
  EXPECT_EQ(s.referencedFiles.size(), 3u);
}

// ------------------------------------------------------------------------------------------------------
// BSDFs and textures
// ------------------------------------------------------------------------------------------------------

TEST(MitsubaLoader, BsdfTypesAndParameters) {
  TempDir d;
  d.write("tex/wood.png", "not really a png; the loader only checks that it exists");
  const SceneDesc s = loadBody(d, R"(
  <bsdf type="diffuse" id="d0"><rgb name="reflectance" value="0.5, 0.2, 0.1"/></bsdf>
  <bsdf type="diffuse" id="d1"><spectrum name="reflectance" value="400:0.3, 500:0.3, 700:0.3"/></bsdf>
  <bsdf type="diffuse" id="d2"><texture type="bitmap" name="reflectance">
      <string name="filename" value="tex/wood.png"/><boolean name="raw" value="true"/>
      <string name="filter_type" value="bilinear"/></texture></bsdf>
  <bsdf type="diffuse" id="d3"><texture type="checkerboard" name="reflectance">
      <rgb name="color0" value="0.1"/><rgb name="color1" value="0.9"/>
      <transform name="to_uv"><scale x="4" y="8"/><translate x="0.5"/></transform></texture></bsdf>
  <bsdf type="twosided" id="two"><ref id="d0"/></bsdf>
  <bsdf type="dielectric" id="glass"/>
  <bsdf type="thindielectric" id="thin"><string name="int_ior" value="water"/><float name="ext_ior" value="1.1"/></bsdf>
  <bsdf type="conductor" id="mirror"/>
  <bsdf type="conductor" id="gold"><string name="material" value="Au"/></bsdf>
  <bsdf type="roughconductor" id="rc"><rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9, 2.4, 2.1"/>
      <string name="distribution" value="ggx"/><float name="alpha" value="0.05"/></bsdf>
  <bsdf type="roughdielectric" id="rd"><float name="alpha_u" value="0.2"/><float name="alpha_v" value="0.2"/>
      <string name="int_ior" value="diamond"/></bsdf>
  <bsdf type="plastic" id="pl"><rgb name="diffuse_reflectance" value="0.2"/><boolean name="nonlinear" value="true"/></bsdf>
  <bsdf type="twosided" id="two2"><bsdf type="roughplastic"><float name="alpha" value="0.3"/></bsdf></bsdf>
  <texture type="checkerboard" id="checks"><float name="uscale" value="2"/></texture>
  <bsdf type="diffuse" id="d4"><ref name="reflectance" id="checks"/></bsdf>
)");
  auto byId = [&](const std::string& id) -> const BsdfDesc& {
    for (const BsdfDesc& b : s.bsdfs)
      if (b.id == id) return b;
    throw std::runtime_error("no bsdf " + id);
  };
  using T = BsdfDesc::Type;
  expectColor(byId("d0").reflectance.value, {0.5f, 0.2f, 0.1f});
  EXPECT_EQ(byId("d0").reflectance.type, TextureDesc::Type::Constant);
  expectColor(byId("d1").reflectance.value, Color(0.3f));
  const TextureDesc& bm = byId("d2").reflectance;
  EXPECT_EQ(bm.type, TextureDesc::Type::Bitmap);
  EXPECT_FALSE(bm.srgb);
  EXPECT_TRUE(fs::path(bm.filename).is_absolute());
  EXPECT_TRUE(fs::equivalent(bm.filename, d.path() / "tex/wood.png"));
  const TextureDesc& cb = byId("d3").reflectance;
  EXPECT_EQ(cb.type, TextureDesc::Type::Checkerboard);
  expectColor(cb.color0, Color(0.1f));
  expectColor(cb.color1, Color(0.9f));
  // to_uv = translate(0.5, 0) * scale(4, 8): uv' = (4u + 0.5, 8v).
  EXPECT_FLOAT_EQ(cb.uvScale.x, 4);
  EXPECT_FLOAT_EQ(cb.uvScale.y, 8);
  EXPECT_FLOAT_EQ(cb.uvOffset.x, 0.5f);
  EXPECT_FLOAT_EQ(cb.uvOffset.y, 0);
  EXPECT_EQ(byId("two").type, T::TwoSided);
  EXPECT_EQ(s.bsdfs.at(byId("two").nested).id, "d0");
  EXPECT_EQ(byId("glass").type, T::Dielectric);
  EXPECT_FLOAT_EQ(byId("glass").intIOR, 1.5046f);
  EXPECT_FLOAT_EQ(byId("glass").extIOR, 1.000277f);
  EXPECT_EQ(byId("thin").type, T::ThinDielectric);
  EXPECT_FLOAT_EQ(byId("thin").intIOR, 1.333f);
  EXPECT_FLOAT_EQ(byId("thin").extIOR, 1.1f);
  EXPECT_TRUE(byId("mirror").mirror);  // 3.x default material = none
  EXPECT_FALSE(byId("gold").mirror);
  EXPECT_NEAR(byId("gold").eta.b, 1.4425f, 1e-3f);
  EXPECT_EQ(byId("rc").type, T::RoughConductor);
  EXPECT_EQ(byId("rc").distribution, MicrofacetType::GGX);
  EXPECT_FLOAT_EQ(byId("rc").alpha, 0.05f);
  expectColor(byId("rc").eta, {0.2f, 0.9f, 1.1f});
  expectColor(byId("rc").k, {3.9f, 2.4f, 2.1f});
  EXPECT_EQ(byId("rd").type, T::RoughDielectric);
  EXPECT_FLOAT_EQ(byId("rd").alpha, 0.2f);
  EXPECT_FLOAT_EQ(byId("rd").intIOR, 2.419f);
  EXPECT_EQ(byId("rd").distribution, MicrofacetType::Beckmann);
  EXPECT_EQ(byId("pl").type, T::Plastic);
  EXPECT_TRUE(byId("pl").nonlinear);
  expectColor(byId("pl").reflectance.value, Color(0.2f));
  const BsdfDesc& inner = s.bsdfs.at(byId("two2").nested);
  EXPECT_EQ(inner.type, T::RoughPlastic);
  EXPECT_FLOAT_EQ(inner.alpha, 0.3f);
  EXPECT_EQ(byId("d4").reflectance.type, TextureDesc::Type::Checkerboard);
  EXPECT_FLOAT_EQ(byId("d4").reflectance.uvScale.x, 2);
  EXPECT_EQ(s.referencedFiles.size(), 1u);
}

TEST(MitsubaLoader, NamedRefsToBsdfs) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <bsdf type="diffuse" id="w"><rgb name="reflectance" value="0.3"/></bsdf>
  <bsdf type="twosided" id="two"><ref name="bsdf" id="w"/></bsdf>
  <shape type="cube"><ref name="bsdf" id="two"/></shape>
  <shape type="cube"><bsdf type="diffuse" name="bsdf" id="inline"/></shape>
  <shape type="cube"><ref id="inline"/></shape>
)");
  ASSERT_EQ(s.meshes.size(), 3u);
  EXPECT_EQ(s.bsdfs.at(s.meshes[0].bsdf).id, "two");
  EXPECT_EQ(s.bsdfs.at(s.bsdfs.at(s.meshes[0].bsdf).nested).id, "w");
  EXPECT_EQ(s.meshes[2].bsdf, s.meshes[1].bsdf);
  EXPECT_TRUE(s.warnings.size() == 1u);  // only: no sensor
}

// The shape of the 0.5/0.6 scenes in Bitterli's rendering resources (exported from Tungsten).
TEST(MitsubaLoader, BitterliStyle06Scene) {
  TempDir d;
  fs::create_directories(d.path() / "models");
  fs::copy_file(kData + "/quad.obj", d.path() / "models/Mesh001.obj", fs::copy_options::overwrite_existing);
  const SceneDesc s = loadBody(d, R"(
	<integrator type="path">
		<integer name="maxDepth" value="65"/>
		<boolean name="strictNormals" value="true"/>
	</integrator>
	<sensor type="perspective">
		<float name="farClip" value="100"/>
		<float name="focusDistance" value="6.8"/>
		<float name="fov" value="19.5"/>
		<string name="fovAxis" value="x"/>
		<float name="nearClip" value="0.1"/>
		<transform name="toWorld">
			<lookat target="0, 1, 5.8" origin="0, 1, 6.8" up="0, 1, 0"/>
		</transform>
		<sampler type="independent">
			<integer name="sampleCount" value="64"/>
		</sampler>
		<film type="ldrfilm">
			<integer name="width" value="1024"/>
			<integer name="height" value="1024"/>
			<string name="fileFormat" value="png"/>
			<string name="pixelFormat" value="rgb"/>
			<float name="gamma" value="2.2"/>
			<boolean name="banner" value="false"/>
			<rfilter type="tent"/>
		</film>
	</sensor>
	<bsdf type="twosided" id="LeftWall">
		<bsdf type="diffuse">
			<rgb name="reflectance" value="0.63, 0.065, 0.05"/>
		</bsdf>
	</bsdf>
	<bsdf type="twosided" id="Light">
		<bsdf type="diffuse">
			<rgb name="reflectance" value="0, 0, 0"/>
		</bsdf>
	</bsdf>
	<shape type="obj">
		<string name="filename" value="models/Mesh001.obj"/>
		<transform name="toWorld">
			<matrix value="-4.37114e-008 1 4.37114e-008 0 0 -8.74228e-008 2 0 4 4.37114e-008 1.91069e-015 0 0 0 0 1"/>
		</transform>
		<boolean name="faceNormals" value="true"/>
		<ref id="LeftWall"/>
	</shape>
	<shape type="rectangle">
		<transform name="toWorld">
			<matrix value="0.235 0 0 -0.005 0 -1.73 -0.19 1.98 0 0.19 -1.7 -0.03 0 0 0 1"/>
		</transform>
		<ref id="Light"/>
		<emitter type="area">
			<rgb name="radiance" value="17, 12, 4"/>
		</emitter>
	</shape>
)",
                               "0.5.0");
  EXPECT_EQ(s.maxDepth, 65);
  EXPECT_EQ(s.camera.width, 1024);
  EXPECT_EQ(s.sampleCount, 64);
  EXPECT_EQ(s.warnings.size(), 2u);  // ldrfilm read as hdrfilm; tent -> box
  ASSERT_EQ(s.meshes.size(), 2u);
  EXPECT_TRUE(s.meshes[0].normals.empty());
  EXPECT_EQ(s.bsdfs.at(s.meshes[0].bsdf).type, BsdfDesc::Type::TwoSided);
  EXPECT_TRUE(s.meshes[1].emission.has_value());
}

TEST(MitsubaLoader, ColourForms) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <bsdf type="diffuse" id="a"><rgb name="reflectance" value="0.5 0.25 0.125"/></bsdf>
  <bsdf type="diffuse" id="b"><srgb name="reflectance" value="#ff8000"/></bsdf>
  <bsdf type="diffuse" id="c"><spectrum name="reflectance" value="0.7"/></bsdf>
  <bsdf type="diffuse" id="e"><float name="reflectance" value="0.2"/></bsdf>
)");
  ASSERT_EQ(s.bsdfs.size(), 4u);
  expectColor(s.bsdfs[0].reflectance.value, {0.5f, 0.25f, 0.125f});
  // sRGB decoding: 0x80 = 128/255 -> ((0.502 + 0.055) / 1.055)^2.4 = 0.2159.
  expectColor(s.bsdfs[1].reflectance.value, {1.0f, 0.21586f, 0.0f}, 1e-4f);
  expectColor(s.bsdfs[2].reflectance.value, Color(0.7f));
  expectColor(s.bsdfs[3].reflectance.value, Color(0.2f));
  expectError(d, sceneXml("  <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5, 0.5\"/></bsdf>\n"), 2, "1 or 3 numbers");
  expectError(d, sceneXml("  <sensor type=\"thinlens\"><float name=\"fov\" value=\"30\"/></sensor>\n"), 2, "aperture_radius");
  expectError(d, sceneXml("  <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"-0.5\"/></bsdf>\n"), 2, "non-negative");
}

// ------------------------------------------------------------------------------------------------------
// Emitters
// ------------------------------------------------------------------------------------------------------

TEST(MitsubaLoader, Emitters) {
  TempDir d;
  const SceneDesc s = loadBody(d, R"(
  <emitter type="point"><point name="position" value="1, 2, 3"/><rgb name="intensity" value="4, 5, 6"/></emitter>
  <emitter type="point"><transform name="to_world"><translate x="-1"/></transform></emitter>
  <emitter type="directional"><vector name="direction" x="0" y="-2" z="0"/><spectrum name="irradiance" value="3"/></emitter>
  <emitter type="directional"><transform name="to_world"><lookat origin="0,0,0" target="1,0,0" up="0,1,0"/></transform></emitter>
  <emitter type="constant"><rgb name="radiance" value="0.25"/></emitter>
  <emitter type="spot"><float name="cutoff_angle" value="40"/></emitter>
  <shape type="rectangle"><bsdf type="diffuse"/><emitter type="area"><rgb name="radiance" value="7, 8, 9"/></emitter></shape>
)");
  ASSERT_EQ(s.lights.size(), 6u);
  EXPECT_EQ(s.lights[0].type, LightDesc::Type::Point);
  expectVec(s.lights[0].position, {1, 2, 3});
  expectColor(s.lights[0].intensity, {4, 5, 6});
  expectVec(s.lights[1].position, {-1, 0, 0});
  EXPECT_EQ(s.lights[2].type, LightDesc::Type::Directional);
  expectVec(s.lights[2].direction, {0, -1, 0});
  expectColor(s.lights[2].intensity, Color(3));
  expectVec(s.lights[3].direction, {1, 0, 0});
  EXPECT_EQ(s.lights[4].type, LightDesc::Type::Constant);
  expectColor(s.lights[4].intensity, Color(0.25f));
  EXPECT_EQ(s.lights[5].type, LightDesc::Type::Spot);
  EXPECT_FLOAT_EQ(s.lights[5].cutoffAngleDeg, 40);
  EXPECT_FLOAT_EQ(s.lights[5].beamWidthDeg, 30);  // Mitsuba: 3/4 of the cutoff
  expectVec(s.lights[5].direction, {0, 0, 1});
  ASSERT_EQ(s.meshes.size(), 1u);
  ASSERT_TRUE(s.meshes[0].emission.has_value());
  expectColor(*s.meshes[0].emission, {7, 8, 9});
}

// ------------------------------------------------------------------------------------------------------
// Defaults, $substitution, includes, refs
// ------------------------------------------------------------------------------------------------------

TEST(MitsubaLoader, DefaultsSubstitutionIncludesAndRefs) {
  TempDir d;
  d.write("parts/walls.xml", R"(<scene version="3.0.0">
  <bsdf type="diffuse" id="wall"><rgb name="reflectance" value="$albedo"/></bsdf>
  <include filename="more/light.xml"/>
</scene>
)");
  d.write("parts/more/light.xml", R"(<scene version="3.0.0">
  <shape type="rectangle"><ref id="wall"/><emitter type="area"><rgb name="radiance" value="$Le"/></emitter></shape>
</scene>
)");
  const std::string body = R"(
  <default name="albedo" value="0.25"/>
  <default name="Le" value="3"/>
  <default name="w" value="64"/>
  <sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="$w"/><integer name="height" value="$w"/></film></sensor>
  <include filename="parts/walls.xml"/>
)";
  const SceneDesc s = loadBody(d, body);
  EXPECT_EQ(s.camera.width, 64);
  ASSERT_EQ(s.meshes.size(), 1u);
  expectColor(s.bsdfs.at(s.meshes[0].bsdf).reflectance.value, Color(0.25f));
  expectColor(*s.meshes[0].emission, Color(3));
  EXPECT_EQ(s.referencedFiles.size(), 2u);
  // Command-line defines override <default>.
  const SceneDesc s2 = loadBody(d, body, "3.0.0", {{"albedo", "0.75"}, {"w", "16"}});
  EXPECT_EQ(s2.camera.width, 16);
  expectColor(s2.bsdfs.at(s2.meshes[0].bsdf).reflectance.value, Color(0.75f));
  expectColor(*s2.meshes[0].emission, Color(3));
}

// ------------------------------------------------------------------------------------------------------
// Malformed input: SceneError naming the file and the right line
// ------------------------------------------------------------------------------------------------------

TEST(MitsubaLoaderErrors, BrokenXml) {
  TempDir d;
  expectError(d, sceneXml("  <shape type=\"cube\">\n  </bsdf>\n"), 3, "does not match");
  expectError(d, "<scene version=\"3.0.0\">\n<shape type=\"cube\"/>\n", 1, "never closed");
}

TEST(MitsubaLoaderErrors, MissingFilesAndIncludes) {
  TempDir d;
  expectError(d, sceneXml("\n  <shape type=\"obj\">\n    <string name=\"filename\" value=\"nope.obj\"/>\n  </shape>\n"), 4,
              "nope.obj");
  expectError(d, sceneXml("  <include filename=\"missing.xml\"/>\n"), 2, "missing.xml");
  d.write("tex_scene_dummy.txt", "");
  expectError(d, sceneXml("  <bsdf type=\"diffuse\">\n    <texture type=\"bitmap\" name=\"reflectance\">\n"
                          "      <string name=\"filename\" value=\"gone.png\"/>\n    </texture>\n  </bsdf>\n"),
              4, "gone.png");
  // Errors inside an included file name that file and its line.
  d.write("inc.xml", "<scene version=\"3.0.0\">\n\n  <shape type=\"teapot\"/>\n</scene>\n");
  try {
    loadMitsubaScene(d.write("scene.xml", sceneXml("  <include filename=\"inc.xml\"/>\n")));
    ADD_FAILURE();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("inc.xml:3:"), std::string::npos) << e.what();
  }
  // A malformed mesh: the XML location and the mesh file are both named.
  d.write("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                     "end_header\n1 2 oops\n");
  expectError(d, sceneXml("  <shape type=\"ply\"><string name=\"filename\" value=\"bad.ply\"/></shape>\n"), 2, "bad.ply:8");
}

TEST(MitsubaLoaderErrors, UnknownPluginsAndParameters) {
  TempDir d;
  expectError(d, sceneXml("\n  <shape type=\"teapot\"/>\n"), 3, "teapot");
  expectError(d, sceneXml("  <bsdf type=\"phong\"/>\n"), 2, "phong");
  expectError(d, sceneXml("  <emitter type=\"envmap\"/>\n"), 2, "envmap");
  expectError(d, sceneXml("  <sensor type=\"orthographic\"/>\n"), 2, "orthographic");
  expectError(d, sceneXml("  <sensor type=\"perspective\"><film type=\"specfilm\"/></sensor>\n"), 2, "specfilm");
  expectError(d, sceneXml("  <bsdf type=\"diffuse\"><texture type=\"noise\" name=\"reflectance\"/></bsdf>\n"), 2, "noise");
  expectError(d, sceneXml("  <medium type=\"homogeneous\"/>\n"), 2, "media");
  expectError(d, sceneXml("  <bsdf type=\"diffuse\">\n\n    <float name=\"roughness\" value=\"0.5\"/>\n  </bsdf>\n"), 4,
              "roughness");
  expectError(d, sceneXml("  <bsdf type=\"diffuse\">\n    <rgb name=\"reflectance\" value=\"0.5\"/>\n"
                          "    <rgb name=\"reflectance\" value=\"0.5\"/>\n  </bsdf>\n"),
              4, "twice");
  expectError(d, sceneXml("  <shape type=\"cube\">\n    <bogus/>\n  </shape>\n"), 3, "unknown element");
  expectError(d, sceneXml("  <shape type=\"cube\"><ref id=\"nothere\"/></shape>\n"), 2, "nothere");
  expectError(d, sceneXml("  <bsdf type=\"conductor\"><string name=\"material\" value=\"Unobtainium\"/></bsdf>\n"), 2,
              "Unobtainium");
  expectError(d, sceneXml("  <bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"jelly\"/></bsdf>\n"), 2, "jelly");
  expectError(d, sceneXml("  <bsdf type=\"diffuse\"><float name=\"reflectance\" valu=\"0.5\"/></bsdf>\n"), 2, "valu");
}

TEST(MitsubaLoaderErrors, BadNumbersAndNaN) {
  TempDir d;
  expectError(d, sceneXml("\n  <sensor type=\"perspective\"><float name=\"fov\" value=\"4o\"/></sensor>\n"), 3, "not a number");
  expectError(d, sceneXml("  <sensor type=\"perspective\">\n    <transform name=\"to_world\">\n"
                          "      <translate x=\"nan\"/>\n    </transform>\n  </sensor>\n"),
              4, "finite");
  expectError(d, sceneXml("  <shape type=\"cube\"><transform name=\"to_world\">\n"
                          "    <matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 inf\"/></transform></shape>\n"),
              3, "finite");
  expectError(d, sceneXml("  <shape type=\"cube\"><transform name=\"to_world\">\n"
                          "    <matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0\"/></transform></shape>\n"),
              3, "16 numbers");
  expectError(d, sceneXml("  <sensor type=\"perspective\"><film type=\"hdrfilm\">\n"
                          "    <integer name=\"width\" value=\"12.5\"/></film></sensor>\n"),
              3, "not an integer");
  expectError(d, sceneXml("  <shape type=\"cube\"><boolean name=\"flip_normals\" value=\"yes\"/></shape>\n"), 2,
              "boolean");
  expectError(d, sceneXml("  <bsdf type=\"diffuse\">\n    <spectrum name=\"reflectance\" value=\"400:0.1, 700:0.9\"/></bsdf>\n"),
              3, "uniform");
  expectError(d, sceneXml("  <shape type=\"sphere\"><float name=\"radius\" value=\"1e999\"/></shape>\n"), 2, "finite");
  expectError(d, sceneXml("  <sensor type=\"perspective\"><float name=\"fov\" value=\"$fov\"/></sensor>\n"), 2, "$fov");
  expectError(d, sceneXml("  <shape type=\"cube\"><transform name=\"to_world\">\n"
                          "    <rotate angle=\"30\"/></transform></shape>\n"),
              3, "axis");
}

TEST(MitsubaLoaderErrors, UnsupportedFeatures) {
  TempDir d;
  expectError(d, sceneXml("  <bsdf type=\"roughconductor\">\n    <float name=\"alpha_u\" value=\"0.1\"/>\n"
                          "    <float name=\"alpha_v\" value=\"0.3\"/>\n  </bsdf>\n"),
              4, "anisotropic");
  expectError(d, sceneXml("  <bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"phong\"/></bsdf>\n"), 2,
              "phong");
  expectError(d, sceneXml("  <bsdf type=\"twosided\"><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>\n"), 2,
              "exactly one");
  expectError(d, sceneXml("  <emitter type=\"area\"/>\n"), 2, "inside a <shape>");
  d.write("t.exr", "x");
  expectError(d, sceneXml("  <bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\">\n"
                          "    <string name=\"filename\" value=\"t.exr\"/></texture></bsdf>\n"),
              3, "PNG");
}

// Truncated and corrupted scene files give a SceneError (or load), never another exception or a crash.
TEST(MitsubaLoaderErrors, TruncatedAndCorruptedFilesOnlyThrowSceneError) {
  TempDir d;
  std::ifstream in(kScenes + "/door-ajar.xml");
  const std::string full((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(full.size(), 1000u);
  Pcg32 rng(7, 11);
  int errors = 0, trials = 0;
  auto attempt = [&](const std::string& text) {
    ++trials;
    try {
      loadMitsubaScene(d.write("scene.xml", text));
    } catch (const SceneError& e) {
      ++errors;
      EXPECT_NE(std::string(e.what()).find("scene.xml"), std::string::npos) << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a SceneError: " << e.what();
    }
  };
  for (size_t n = 0; n < full.size(); n += 97) attempt(full.substr(0, n));
  const std::string junk = "<>\"'&$=/ x9.-";
  for (int i = 0; i < 60; ++i) {
    std::string t = full;
    for (int k = 0; k < 3; ++k) t[rng.bounded(uint32_t(t.size()))] = junk[rng.bounded(uint32_t(junk.size()))];
    attempt(t);
  }
  EXPECT_GT(errors, trials / 2);
  attempt("<scene version=\"3.0.0\">" + [] { std::string s; for (int i = 0; i < 2000; ++i) s += "<a>"; return s; }());
}

// ------------------------------------------------------------------------------------------------------
// Bundled scenes
// ------------------------------------------------------------------------------------------------------

TEST(BundledScenes, AllLoadWithoutWarnings) {
  int count = 0;
  for (const auto& e : fs::directory_iterator(kScenes)) {
    const bool pbrt = e.path().extension() == ".pbrt";
    if (e.path().extension() != ".xml" && !pbrt) continue;
    ++count;
    SCOPED_TRACE(e.path().string());
    const SceneDesc s = loadScene(e.path().string());
    EXPECT_TRUE(s.warnings.empty()) << (s.warnings.empty() ? "" : s.warnings[0]);
    EXPECT_FALSE(s.meshes.empty());
    bool emits = !s.lights.empty();
    for (const MeshDesc& m : s.meshes) emits = emits || m.emission.has_value();
    EXPECT_TRUE(emits);
    EXPECT_TRUE(s.maxDepth.has_value());
    // The first line after the prolog is the one-line comment on what the scene stresses (pbrt: line 1).
    std::ifstream in(e.path());
    std::string l1, l2;
    std::getline(in, l1);
    std::getline(in, l2);
    if (pbrt) EXPECT_EQ(l1.rfind("# Stresses: ", 0), 0u) << l1;
    else EXPECT_EQ(l2.rfind("<!-- Stresses: ", 0), 0u) << l2;
  }
  EXPECT_GE(count, 8);
}

TEST(BundledScenes, CornellBoxIsTheClassic) {
  const SceneDesc s = loadMitsubaScene(kScenes + "/cornell-box.xml");
  EXPECT_EQ(s.maxDepth, 5);
  EXPECT_EQ(s.camera.width, 256);
  EXPECT_EQ(s.camera.height, 256);
  ASSERT_EQ(s.meshes.size(), 8u);
  int emitters = 0;
  for (const MeshDesc& m : s.meshes) {
    if (m.emission) {
      ++emitters;
      for (size_t t = 0; t < m.indices.size() / 3; ++t) expectVec(triNormal(m, t), {0, -1, 0});
      EXPECT_NEAR(meshArea(m), 0.47 * 0.38, 1e-5);
    }
  }
  EXPECT_EQ(emitters, 1);
  // The five walls face the inside of the box; red is at x = -1 (image left for this camera).
  for (size_t w = 0; w < 5; ++w) {
    const MeshDesc& m = s.meshes[w];
    for (size_t t = 0; t < 2; ++t) EXPECT_GT(dot(triNormal(m, t), Vec3(0, 1, 0) - triCentroid(m, t)), 0.0f);
    if (s.bsdfs[m.bsdf].id == "red") {
      EXPECT_NEAR(triCentroid(m, 0).x, -1.0f, 1e-6f);
    }
  }
  // Camera +x (image left) is world -x: the red wall is on the left.
  expectVec(s.camera.toWorld.vector({1, 0, 0}), {-1, 0, 0});
}

TEST(BundledScenes, FurnaceSphereParameters) {
  const SceneDesc s = loadMitsubaScene(kScenes + "/furnace-sphere.xml", {{"rho", "0.8"}, {"Le", "2"}});
  ASSERT_EQ(s.meshes.size(), 1u);
  expectColor(*s.meshes[0].emission, Color(2));
  expectColor(s.bsdfs.at(s.meshes[0].bsdf).reflectance.value, Color(0.8f));
  EXPECT_EQ(s.maxDepth, -1);
  EXPECT_TRUE(s.meshes[0].normals.empty());
  const MeshDesc& m = s.meshes[0];
  for (size_t t = 0; t < m.indices.size() / 3; ++t) EXPECT_LT(dot(triNormal(m, t), triCentroid(m, t)), 0.0f);  // inward
}

// ------------------------------------------------------------------------------------------------------
// Scene content hash
// ------------------------------------------------------------------------------------------------------

TEST(SceneHash, CoversReferencedFilesAndIgnoresLocation) {
  TempDir a, b;
  const std::string xml = sceneXml("  <shape type=\"obj\"><string name=\"filename\" value=\"m/quad.obj\"/></shape>\n");
  for (const TempDir* d : {&a, &b}) {
    fs::create_directories(d->path() / "m");
    fs::copy_file(kData + "/quad.obj", d->path() / "m/quad.obj", fs::copy_options::overwrite_existing);
    d->write("scene.xml", xml);
  }
  const SceneDesc sa = loadMitsubaScene((a.path() / "scene.xml").string());
  const SceneDesc sb = loadMitsubaScene((b.path() / "scene.xml").string());
  const std::string ha = sceneContentHash(sa);
  EXPECT_EQ(ha.size(), 64u);
  EXPECT_EQ(ha, sceneContentHash(sb));  // same bundle in another folder
  const auto files = sceneBundleFiles(sa);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].relativePath, "m/quad.obj");
  EXPECT_EQ(files[1].relativePath, "scene.xml");
  // Editing a referenced file changes the hash.
  std::ofstream(b.path() / "m/quad.obj", std::ios::app) << "# edited\n";
  EXPECT_NE(ha, sceneContentHash(sb));
  // So does editing the scene file itself.
  a.write("scene.xml", xml + "\n");
  EXPECT_NE(ha, sceneContentHash(sa));
}

// Three values the loader used to accept and the render scene refused later, without a line (issue 13's
// loader fuzzing): now refused at load, naming file and line.
TEST(MitsubaLoader, ValuesTheRenderSceneRefusesAreRefusedAtLoadWithTheirLine) {
  TempDir d;
  // A spot light's cutoff_angle 180 (the spot light takes (0, 180)).
  expectError(d, sceneXml("<emitter type=\"spot\">\n  <float name=\"cutoff_angle\" value=\"180\"/>\n</emitter>\n"), 3,
              "cutoff_angle must be in (0, 180)");
  // A sensor's to_world that stretches one axis (a camera frame needs a similarity).
  expectError(d, sceneXml("<sensor type=\"perspective\">\n  <transform name=\"to_world\">\n"
                          "    <scale x=\"2\" y=\"1\" z=\"1\"/>\n  </transform>\n</sensor>\n"),
              3, "to_world must be a rotation, translation, uniform scale or mirror");
  // An emitting shape scaled to nothing (an area light needs a positive area).
  expectError(d, sceneXml("<shape type=\"rectangle\">\n  <transform name=\"to_world\"><scale value=\"0\"/></transform>\n"
                          "  <emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>\n</shape>\n"),
              2, "an emitting shape must have a positive, finite area");
  // What stays accepted: a cutoff just under 180, a uniformly scaled and mirrored camera, a lit rectangle.
  const SceneDesc ok = loadBody(d, "<emitter type=\"spot\"><float name=\"cutoff_angle\" value=\"179\"/></emitter>\n"
                                   "<sensor type=\"perspective\"><transform name=\"to_world\"><scale x=\"-2\" y=\"2\" z=\"2\"/>"
                                   "</transform></sensor>\n"
                                   "<shape type=\"rectangle\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n");
  EXPECT_EQ(ok.lights.size(), 1u);
  EXPECT_EQ(ok.meshes.size(), 1u);
}

}  // namespace
}  // namespace mlt
