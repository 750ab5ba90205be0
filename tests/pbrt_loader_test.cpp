// The pbrt-v3 front end: directives, conventions (handedness, maxdepth, roughness remap, texture
// coordinates), errors naming file, line and construct, and one scene written in both formats that must
// render to the same image (mean and tile means) with pt, lt and bdpt.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "tests/support/temp_dir.h"
#include "common/integrators/evaluators.h"
#include "common/render/render_scene.h"
#include "common/scene/mitsuba_loader.h"
#include "common/scene/pbrt_loader.h"
#include "common/scene/scene_loader.h"
#include "tests/support/estimates.h"
#include "tests/support/mlt_stats.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
#pragma GCC diagnostic pop

namespace fs = std::filesystem;

namespace mlt {
namespace {

const std::string kCamera = "Scale -1 1 1\nLookAt 0 1 5  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n";

SceneDesc loadPbrt(const TempDir& d, const std::string& text, const std::string& name = "scene.pbrt") {
  return loadScene(d.write(name, text));
}

void expectError(const TempDir& d, const std::string& text, int line, const std::string& what) {
  try {
    loadPbrt(d, text);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const SceneError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("scene.pbrt:" + std::to_string(line) + ":"), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
}

void expectVec(const Vec3& a, const Vec3& b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

const std::string kTriangle = "Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 0 0 1 0 0 0 1 0]\n";

// ------------------------------------------------------------------------------------------------------
TEST(PbrtLoader, CameraHandednessFilmSamplerAndDepth) {
  TempDir d;
  const SceneDesc s = loadPbrt(d, kCamera + R"(Film "image" "integer xresolution" 32 "integer yresolution" 16 "string filename" "x.exr"
Sampler "halton" "integer pixelsamples" 64
Integrator "path" "integer maxdepth" 4
WorldBegin
WorldEnd
)");
  EXPECT_EQ(s.camera.width, 32);
  EXPECT_EQ(s.camera.height, 16);
  EXPECT_EQ(s.sampleCount, 64);
  ASSERT_TRUE(s.maxDepth.has_value());
  EXPECT_EQ(*s.maxDepth, 5);  // 4 bounces = 5 segments
  EXPECT_FLOAT_EQ(s.camera.fovDeg, 40.0f);
  EXPECT_EQ(s.camera.fovAxis, CameraDesc::FovAxis::Smaller);
  // With `Scale -1 1 1` before LookAt, pbrt's camera equals Mitsuba's <lookat> with the same arguments.
  const Transform mitsuba = Transform::lookAt({0, 1, 5}, {0, 1, 0}, {0, 1, 0});
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(s.camera.toWorld.m[r][c], mitsuba.m[r][c], 1e-9) << r << c;
  // Without it the image is mirrored: the camera's x axis (column 0 of toWorld) flips sign.
  const SceneDesc m = loadPbrt(d, "LookAt 0 1 5  0 1 0  0 1 0\nCamera \"perspective\"\nWorldBegin\nWorldEnd\n");
  EXPECT_NEAR(m.camera.toWorld.m[0][0], -mitsuba.m[0][0], 1e-9);
  EXPECT_NEAR(m.camera.toWorld.m[1][1], mitsuba.m[1][1], 1e-9);
  EXPECT_EQ(*m.maxDepth, 6);  // no Integrator: pbrt's default maxdepth 5
  EXPECT_EQ(m.camera.width, 640);
  EXPECT_FLOAT_EQ(m.camera.fovDeg, 90.0f);
  // Thin lens.
  const SceneDesc t = loadPbrt(d, "Camera \"perspective\" \"float lensradius\" 0.1 \"float focaldistance\" 3\nWorldBegin\n");
  EXPECT_EQ(t.camera.type, CameraDesc::Type::ThinLens);
  EXPECT_FLOAT_EQ(t.camera.apertureRadius, 0.1f);
  EXPECT_FLOAT_EQ(t.camera.focusDistance, 3.0f);
}

TEST(PbrtLoader, TransformsAttributesAndInstances) {
  TempDir d;
  const SceneDesc s = loadPbrt(d, kCamera + "WorldBegin\n" +
                                      "AttributeBegin\n Translate 1 2 3\n" + kTriangle +
                                      " TransformBegin\n  Scale 2 2 2\n" + kTriangle +
                                      " TransformEnd\n" + kTriangle + "AttributeEnd\n" +
                                      "AttributeBegin\n Rotate 90 0 0 1\n" + kTriangle + "AttributeEnd\n" +
                                      "AttributeBegin\n Transform [1 0 0 0  0 1 0 0  0 0 1 0  5 0 0 1]\n" + kTriangle +
                                      " ConcatTransform [2 0 0 0  0 2 0 0  0 0 2 0  0 0 0 1]\n" + kTriangle + "AttributeEnd\n" +
                                      "ObjectBegin \"tri\"\n Translate 0 0 1\n" + kTriangle + "ObjectEnd\n" +
                                      "AttributeBegin\n Translate 10 0 0\n ObjectInstance \"tri\"\nAttributeEnd\n" +
                                      "ObjectInstance \"tri\"\n" + kTriangle + "WorldEnd\n");
  ASSERT_EQ(s.meshes.size(), 9u);
  expectVec(s.meshes[0].positions[1], {2, 2, 3});
  expectVec(s.meshes[1].positions[1], {3, 2, 3});    // translate then scale 2
  expectVec(s.meshes[2].positions[1], {2, 2, 3});    // TransformEnd restores
  expectVec(s.meshes[3].positions[1], {0, 1, 0});    // Rotate 90 about z: x -> y
  expectVec(s.meshes[4].positions[1], {6, 0, 0});    // Transform is column-major: translation in the last 4
  expectVec(s.meshes[5].positions[1], {7, 0, 0});    // ConcatTransform multiplies on the right
  expectVec(s.meshes[6].positions[1], {11, 0, 1});   // instance CTM on top of the object's own
  expectVec(s.meshes[7].positions[1], {1, 0, 1});
  expectVec(s.meshes[8].positions[1], {1, 0, 0});    // AttributeEnd / ObjectEnd restored the CTM
}

TEST(PbrtLoader, MaterialsNamedMaterialsAndTextures) {
  TempDir d;
  {
    unsigned char px[4 * 3] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
    ASSERT_TRUE(stbi_write_png((d.path() / "tex.png").string().c_str(), 2, 2, 3, px, 6));
  }
  const SceneDesc s = loadPbrt(d, kCamera + R"(WorldBegin
Texture "checks" "spectrum" "checkerboard" "float uscale" 4 "float vscale" 8 "rgb tex1" [0.8 0.8 0.8] "rgb tex2" [0.1 0.2 0.3]
Texture "img" "spectrum" "imagemap" "string filename" "tex.png" "float vscale" 2
Texture "half" "spectrum" "scale" "texture tex1" "checks" "rgb tex2" [0.5 0.5 0.5]
MakeNamedMaterial "floor" "string type" "matte" "texture Kd" "checks"
LightSource "point" "rgb I" [1 1 1] "point from" [0 3 0]
Material "mirror"
)" + kTriangle + R"(NamedMaterial "floor"
)" + kTriangle + R"(Material "glass" "float eta" 1.33 "float roughness" 0.2
)" + kTriangle + R"(Material "metal" "rgb eta" [0.2 0.9 1.1] "rgb k" [3.9 2.4 2.2] "float roughness" 0.3 "bool remaproughness" "false"
)" + kTriangle + R"(Material "matte" "texture Kd" "img"
)" + kTriangle + R"(Material "plastic" "rgb Kd" [0.3 0.3 0.3] "rgb Ks" [0 0 0]
)" + kTriangle + R"(Material "matte" "texture Kd" "half"
)" + kTriangle + R"(Material "metal" "float roughness" 0
)" + kTriangle + R"(Material "glass"
)" + kTriangle + "WorldEnd\n");
  ASSERT_EQ(s.meshes.size(), 9u);
  auto inner = [&](int mesh) -> const BsdfDesc& {
    const BsdfDesc& b = s.bsdfs.at(s.meshes[mesh].bsdf);
    return b.type == BsdfDesc::Type::TwoSided ? s.bsdfs.at(b.nested) : b;
  };
  EXPECT_EQ(s.bsdfs[s.meshes[0].bsdf].type, BsdfDesc::Type::TwoSided);  // pbrt's materials are two-sided
  EXPECT_EQ(inner(0).type, BsdfDesc::Type::Conductor);
  EXPECT_TRUE(inner(0).mirror);
  EXPECT_FLOAT_EQ(inner(0).specularReflectance.value.r, 0.9f);  // pbrt's mirror Kr default
  const TextureDesc& checks = inner(1).reflectance;
  ASSERT_EQ(checks.type, TextureDesc::Type::Checkerboard);
  EXPECT_FLOAT_EQ(checks.uvScale.x, 2.0f);  // pbrt cells are 1 in s; ours 1/2 in u'
  EXPECT_FLOAT_EQ(checks.uvScale.y, 4.0f);
  EXPECT_FLOAT_EQ(checks.color0.r, 0.8f);
  EXPECT_FLOAT_EQ(checks.color1.b, 0.3f);
  EXPECT_EQ(inner(2).type, BsdfDesc::Type::RoughDielectric);
  EXPECT_EQ(s.bsdfs[s.meshes[2].bsdf].type, BsdfDesc::Type::RoughDielectric);  // glass is not wrapped
  EXPECT_FLOAT_EQ(inner(2).intIOR, 1.33f);
  EXPECT_FLOAT_EQ(inner(2).extIOR, 1.0f);
  EXPECT_FLOAT_EQ(inner(2).alpha, pbrtRoughnessToAlpha(0.2f));
  EXPECT_EQ(inner(2).distribution, MicrofacetType::GGX);
  EXPECT_EQ(inner(3).type, BsdfDesc::Type::RoughConductor);
  EXPECT_FLOAT_EQ(inner(3).alpha, 0.3f);  // remaproughness false
  EXPECT_FLOAT_EQ(inner(3).eta.g, 0.9f);
  const TextureDesc& img = inner(4).reflectance;
  ASSERT_EQ(img.type, TextureDesc::Type::Bitmap);
  EXPECT_TRUE(img.srgb);
  EXPECT_FLOAT_EQ(img.uvScale.y, -2.0f);  // pbrt's t runs up the image
  EXPECT_FLOAT_EQ(img.uvOffset.y, 1.0f);
  EXPECT_EQ(inner(5).type, BsdfDesc::Type::Diffuse);  // plastic with Ks = 0 is Lambertian
  EXPECT_FLOAT_EQ(inner(6).reflectance.color0.r, 0.4f);  // scale: 0.5 * checks
  EXPECT_EQ(inner(7).type, BsdfDesc::Type::Conductor);   // roughness 0: smooth
  EXPECT_EQ(inner(8).type, BsdfDesc::Type::Dielectric);
  EXPECT_FLOAT_EQ(inner(8).intIOR, 1.5f);
  EXPECT_EQ(s.referencedFiles.size(), 1u);  // the image
  // Every material builds, and the roughness remap is pbrt-v3's polynomial.
  EXPECT_NEAR(pbrtRoughnessToAlpha(0.5f), 1.62142 + 0.819955 * std::log(0.5) + 0.1734 * std::pow(std::log(0.5), 2) +
                                              0.0171201 * std::pow(std::log(0.5), 3) + 0.000640711 * std::pow(std::log(0.5), 4),
              1e-5);
  const auto scene = RenderScene::build(s);
  EXPECT_NE(scene, nullptr);
}

TEST(PbrtLoader, LightsAreaLightsAndIncludes) {
  TempDir d;
  d.write("parts/light.pbrt", "AttributeBegin\n AreaLightSource \"diffuse\" \"rgb L\" [2 3 4] \"bool twosided\" \"true\"\n" +
                                  kTriangle + "AttributeEnd\n");
  const SceneDesc s = loadPbrt(d, kCamera + R"(WorldBegin
LightSource "point" "rgb I" [1 2 3] "point from" [0 4 0]
AttributeBegin
  Translate 0 1 0
  LightSource "spot" "rgb I" [5 5 5] "point from" [0 0 0] "point to" [0 -1 0] "float coneangle" 25 "float conedelta" 0
AttributeEnd
LightSource "distant" "rgb L" [1 1 1] "point from" [0 0 0] "point to" [0 0 -1] "rgb scale" [2 2 2]
LightSource "infinite" "rgb L" [0.1 0.2 0.3]
Include "parts/light.pbrt"
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [1 1 1]
  ReverseOrientation
)" + kTriangle + "AttributeEnd\n" + kTriangle + "WorldEnd\n");
  ASSERT_EQ(s.lights.size(), 4u);
  EXPECT_EQ(s.lights[0].type, LightDesc::Type::Point);
  expectVec(s.lights[0].position, {0, 4, 0});
  EXPECT_FLOAT_EQ(s.lights[0].intensity.g, 2.0f);
  EXPECT_EQ(s.lights[1].type, LightDesc::Type::Spot);
  expectVec(s.lights[1].position, {0, 1, 0});
  expectVec(s.lights[1].direction, {0, -1, 0});
  EXPECT_FLOAT_EQ(s.lights[1].cutoffAngleDeg, 25.0f);
  EXPECT_FLOAT_EQ(s.lights[1].beamWidthDeg, 25.0f);
  EXPECT_EQ(s.lights[1].spotFalloff, LightDesc::SpotFalloff::PbrtQuartic);
  EXPECT_EQ(s.lights[2].type, LightDesc::Type::Directional);
  expectVec(s.lights[2].direction, {0, 0, -1});  // travel direction from -> to
  EXPECT_FLOAT_EQ(s.lights[2].intensity.r, 2.0f);
  EXPECT_EQ(s.lights[3].type, LightDesc::Type::Constant);
  // twosided: two meshes facing opposite ways; ReverseOrientation flips; the last triangle does not emit.
  ASSERT_EQ(s.meshes.size(), 4u);
  ASSERT_TRUE(s.meshes[0].emission && s.meshes[1].emission && s.meshes[2].emission);
  EXPECT_FALSE(s.meshes[3].emission.has_value());
  EXPECT_FLOAT_EQ(s.meshes[0].emission->b, 4.0f);
  auto ng = [](const MeshDesc& m) {
    return normalize(cross(m.positions[m.indices[1]] - m.positions[m.indices[0]], m.positions[m.indices[2]] - m.positions[m.indices[0]]));
  };
  expectVec(ng(s.meshes[0]), {0, 0, -1});  // (the back copy comes first)
  expectVec(ng(s.meshes[1]), {0, 0, 1});
  expectVec(ng(s.meshes[2]), {0, 0, -1});  // ReverseOrientation
  expectVec(ng(s.meshes[3]), {0, 0, 1});
  EXPECT_EQ(s.referencedFiles.size(), 1u);
  EXPECT_NE(s.referencedFiles[0].find("light.pbrt"), std::string::npos);
}

TEST(PbrtLoader, ShapesNormalsAndUvs) {
  TempDir d;
  fs::copy_file(std::string(MLTFARM_SOURCE_DIR) + "/tests/data/scenes/quad.ply", d.path() / "quad.ply");
  const SceneDesc s = loadPbrt(d, kCamera + R"(WorldBegin
Shape "trianglemesh" "integer indices" [0 1 2] "point P" [0 0 0 1 0 0 0 1 0] "normal N" [0 0 -1 0 0 -1 0 0 -1] "float uv" [0 0 1 0 0 1]
Shape "plymesh" "string filename" "quad.ply"
Shape "sphere" "float radius" 2
Shape "disk" "float radius" 3 "float height" 1
WorldEnd
)");
  ASSERT_EQ(s.meshes.size(), 4u);
  // The triangle faces its normals (pbrt's FaceForward): winding reversed.
  const MeshDesc& t = s.meshes[0];
  const Vec3 n = cross(t.positions[t.indices[1]] - t.positions[t.indices[0]], t.positions[t.indices[2]] - t.positions[t.indices[0]]);
  EXPECT_LT(n.z, 0.0f);
  EXPECT_EQ(t.uvs.size(), 3u);
  EXPECT_FALSE(s.meshes[1].positions.empty());
  float rMax = 0;
  for (const Vec3& p : s.meshes[2].positions) rMax = std::fmax(rMax, length(p));
  EXPECT_NEAR(rMax, 2.0f, 1e-5);
  for (const Vec3& p : s.meshes[3].positions) EXPECT_NEAR(p.z, 1.0f, 1e-6);
}

// The camera's transform follows the rule of a Mitsuba sensor's to_world (common/scene/camera_transform.h):
// a look-at that defines a frame; finite; a rotation, translation, uniform scale or mirror. Each refusal
// names the file and the line (the LookAt's, else the Camera's).
TEST(PbrtLoader, CameraTransformFollowsTheSensorRule) {
  TempDir d("pbrt_camera_rule");
  const std::string rest = "Camera \"perspective\"\nWorldBegin\n";
  expectError(d, "LookAt 0 1 5  0 1 5  0 1 0\n" + rest, 1, "origin and target coincide");
  expectError(d, "LookAt 0 1 5  0 1 0  0 0 1\n" + rest, 1, "'up' is zero or parallel to the viewing direction");
  expectError(d, "LookAt 0 1 5  0 1 0  0 0 0\n" + rest, 1, "'up' is zero or parallel to the viewing direction");
  expectError(d, "Scale 0 1 1\n" + rest, 2, "must be a rotation, translation, uniform scale or mirror");
  expectError(d, "LookAt 0 1 5  0 1 0  0 1 0\nScale 1 2 1\n" + rest, 3, "must be a rotation, translation, uniform scale or mirror");
  expectError(d, "ConcatTransform [1 0 0 0  0.5 1 0 0  0 0 1 0  0 0 0 1]\n" + rest, 2, "uniform scale");  // sheared
  expectError(d, "Translate 1e39 0 0\n" + rest, 2, "not finite");  // overflows a float: inf, then NaN
  expectError(d, "Translate 1e39 0 0\nRotate 10 0 1 0\n" + rest, 3, "not finite");  // inf * 0: NaN
  expectError(d, "Translate nan 0 0\n" + rest, 1, "nan");
  // What the rule allows: a mirror and a uniform scale (the bundled scenes' Scale -1 1 1).
  EXPECT_NO_THROW(loadPbrt(d, "Scale -2 2 2\nLookAt 0 1 5  0 1 0  0 1 0\n" + rest));
}

TEST(PbrtLoader, ErrorsNameFileLineAndConstruct) {
  TempDir d;
  expectError(d, "Camera \"perspective\"\nWorldBegin\nFrobnicate 1 2\n", 3, "unknown or unsupported directive 'Frobnicate'");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nMaterial \"plastic\" \"rgb Ks\" [0.5 0.5 0.5]\n", 3, "plastic");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nMaterial \"substrate\"\n", 3, "substrate");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nMaterial \"uber\"\n", 3, "uber");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nMaterial \"matte\"\n  \"float sigma\" 20\n", 4, "Oren-Nayar");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nMaterial \"matte\" \"rgb Kd\" [1 1]\n", 3, "three values");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nMaterial \"matte\"\n \"float bogus\" 1\n", 4, "'float bogus'");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nMaterial \"metal\" \"spectrum eta\" \"Au.eta.spd\"\n", 3, "spectrum");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nShape \"cylinder\"\n", 3, "unsupported type 'cylinder'");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nShape \"sphere\" \"float zmax\" 0.5\n", 3, "partial spheres");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nShape \"trianglemesh\" \"integer indices\" [0 1 5] \"point P\" [0 0 0 1 0 0 0 1 0]\n",
              3, "out of range");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nLightSource \"spot\" \"float coneangle\" 10 \"float conedelta\" 12\n", 3,
              "conedelta must be in [0, coneangle]");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nLightSource \"infinite\" \"string mapname\" \"sky.exr\"\n", 3, "environment maps");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nInclude \"missing.pbrt\"\n", 3, "not found");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nNamedMaterial \"nope\"\n", 3, "no material named 'nope'");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nAttributeEnd\n", 3, "AttributeEnd without AttributeBegin");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nShape \"sphere\" \"float radius\n", 3, "unterminated string");
  expectError(d, "Camera \"orthographic\"\n", 1, "unsupported type 'orthographic'");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nMakeNamedMedium \"fog\"\n", 3, "media");
  expectError(d, "Camera \"perspective\"\nWorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"a.exr\"\n", 3,
              "only PNG and JPEG");
  // An error inside an included file names that file.
  d.write("inc.pbrt", "\n\nShape \"cone\"\n");
  try {
    loadPbrt(d, "Camera \"perspective\"\nWorldBegin\nInclude \"inc.pbrt\"\n");
    ADD_FAILURE();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("inc.pbrt:3:"), std::string::npos) << e.what();
  }
  // Truncated input never crashes: every prefix loads or throws SceneError.
  const std::string full = kCamera + "WorldBegin\nAttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n" + kTriangle +
                           "AttributeEnd\nWorldEnd\n";
  for (size_t n = 0; n < full.size(); n += 3) {
    try {
      loadPbrt(d, full.substr(0, n));
    } catch (const SceneError&) {
    }
  }
}

// ------------------------------------------------------------------------------------------------------
// One scene in both formats: a box with a checkerboard floor, a rough metal sphere, a glass sphere and a
// ceiling area light, seen through a 24 x 24 film with max depth 5 segments (pbrt maxdepth 4).
// ------------------------------------------------------------------------------------------------------
const char* kMitsubaTwin = R"(<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="5"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/><string name="fov_axis" value="smaller"/>
    <transform name="to_world"><lookat origin="0, 1, 4.5" target="0, 1, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film>
  </sensor>
  <bsdf type="twosided" id="floor"><bsdf type="diffuse">
    <texture name="reflectance" type="checkerboard"><rgb name="color0" value="0.8, 0.8, 0.8"/><rgb name="color1" value="0.1, 0.2, 0.3"/>
      <transform name="to_uv"><scale x="2" y="2"/></transform></texture></bsdf></bsdf>
  <bsdf type="twosided" id="wall"><bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></bsdf>
  <bsdf type="twosided" id="metal"><bsdf type="roughconductor"><string name="distribution" value="ggx"/>
    <float name="alpha" value="0.2"/><rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9, 2.4, 2.2"/></bsdf></bsdf>
  <bsdf type="dielectric" id="glass"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/></bsdf>
  <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/></transform><ref id="floor"/></shape>
  <shape type="rectangle"><transform name="to_world"><translate z="-1"/></transform><ref id="wall"/></shape>
  <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/></transform><ref id="wall"/></shape>
  <shape type="sphere"><point name="center" x="-0.45" y="0.35" z="-0.2"/><float name="radius" value="0.35"/><ref id="metal"/></shape>
  <shape type="sphere"><point name="center" x="0.45" y="0.35" z="0.2"/><float name="radius" value="0.3"/><ref id="glass"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.25"/><rotate x="1" angle="90"/><translate y="1.99"/></transform>
    <ref id="wall"/><emitter type="area"><rgb name="radiance" value="12, 10, 8"/></emitter></shape>
</scene>
)";

// The same scene in pbrt-v3. Mitsuba's rectangle is [-1,1]^2 at z = 0 facing +z with uv (0,0) at (-1,-1).
const char* kPbrtTwin = R"(# pbrt-v3 twin of the Mitsuba scene above
Integrator "path" "integer maxdepth" 4
Scale -1 1 1
LookAt 0 1 4.5  0 1 0  0 1 0
Camera "perspective" "float fov" 40
Film "image" "integer xresolution" 24 "integer yresolution" 24
WorldBegin
Texture "checks" "spectrum" "checkerboard" "float uscale" 4 "float vscale" 4 "rgb tex1" [0.8 0.8 0.8] "rgb tex2" [0.1 0.2 0.3]
MakeNamedMaterial "floor" "string type" "matte" "texture Kd" "checks"
MakeNamedMaterial "wall" "string type" "matte" "rgb Kd" [0.6 0.5 0.4]
AttributeBegin
  NamedMaterial "floor"
  Rotate -90 1 0 0
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-1 -1 0 1 -1 0 1 1 0 -1 1 0] "float uv" [0 0 1 0 1 1 0 1]
AttributeEnd
AttributeBegin
  NamedMaterial "wall"
  Translate 0 0 -1
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-1 -1 0 1 -1 0 1 1 0 -1 1 0]
AttributeEnd
AttributeBegin
  NamedMaterial "wall"
  Translate 0 2 0
  Rotate 90 1 0 0
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-1 -1 0 1 -1 0 1 1 0 -1 1 0]
AttributeEnd
AttributeBegin
  Material "metal" "rgb eta" [0.2 0.9 1.1] "rgb k" [3.9 2.4 2.2] "float roughness" 0.2 "bool remaproughness" "false"
  Translate -0.45 0.35 -0.2
  Shape "sphere" "float radius" 0.35
AttributeEnd
AttributeBegin
  Material "glass" "float eta" 1.5
  Translate 0.45 0.35 0.2
  Shape "sphere" "float radius" 0.3
AttributeEnd
AttributeBegin
  NamedMaterial "wall"
  AreaLightSource "diffuse" "rgb L" [12 10 8]
  Translate 0 1.99 0
  Rotate 90 1 0 0
  Scale 0.25 0.25 0.25
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-1 -1 0 1 -1 0 1 1 0 -1 1 0]
AttributeEnd
WorldEnd
)";

TEST(PbrtLoader, SameSceneInBothFormatsRendersTheSame) {
  TempDir d;
  const SceneDesc xml = loadScene(d.write("twin.xml", kMitsubaTwin));
  const SceneDesc pbrt = loadScene(d.write("twin.pbrt", kPbrtTwin));
  ASSERT_EQ(xml.maxDepth, pbrt.maxDepth);
  ASSERT_EQ(xml.meshes.size(), pbrt.meshes.size());
  const auto sx = RenderScene::build(xml), sp = RenderScene::build(pbrt);
  IntegratorSettings is;
  is.maxDepth = *xml.maxDepth;
  is.rrDepth = 5;
  // Tolerance from the estimates' own standard errors: |a - b| < 5 sigma over the image mean and 4 x 4
  // tile means (about 17 comparisons per method; the seeds are fixed).
  for (const std::string m : {"pt", "bdpt", "lt"}) {
    // pt and bdpt see the light through the glass sphere (specular chains found only by BSDF sampling):
    // heavy-tailed pixels, so more samples; lt cannot see the sphere at all and converges fast.
    const uint64_t n = m == "lt" ? 24 * 24 * 400 : 24 * 24 * 800;
    const auto ex = makeEvaluator(*sx, m, is), ep = makeEvaluator(*sp, m, is);
    const test::ImageStats a = test::estimateImage(*ex, 24, 24, 11, n, 4, 4);
    const test::ImageStats b = test::estimateImage(*ep, 24, 24, 23, n, 4, 4);
    int where = -1;
    const double z = test::maxZ(a, b, &where);
    std::printf("%-5s mitsuba %.5f +- %.5f  pbrt %.5f +- %.5f  max z %.2f\n", m.c_str(), a.mean[0], a.stdErr[0], b.mean[0],
                b.stdErr[0], z);
    EXPECT_LT(z, 5.0) << m << " entry " << where << ": " << a.mean[where] << " +- " << a.stdErr[where] << " vs "
                      << b.mean[where] << " +- " << b.stdErr[where];
    // The comparison can fail: the error bars resolve 10% of the image mean (as tests/bundled_scenes_test).
    EXPECT_LT(5 * std::hypot(a.stdErr[0], b.stdErr[0]), 0.10 * a.mean[0]) << m;
  }
}

// The Markov chain methods (every registered one besides the sample-based pt/lt/bdpt above) on the pbrt
// twin agree with bdpt on the Mitsuba twin: image mean and 3 x 3 tile means of 12 independent job seeds
// (bootstrap included) within 5 combined standard errors, as tests/mlt_bundled_test.cpp does.
TEST(PbrtLoader, MarkovChainMethodsOnThePbrtTwinAgreeWithTheMitsubaTwin) {
  TempDir d;
  const SceneDesc xml = loadScene(d.write("twin.xml", kMitsubaTwin));
  const SceneDesc pbrt = loadScene(d.write("twin.pbrt", kPbrtTwin));
  const auto sx = RenderScene::build(xml), sp = RenderScene::build(pbrt);
  IntegratorSettings is;
  is.maxDepth = *xml.maxDepth;
  is.rrDepth = 5;
  const auto bdpt = makeEvaluator(*sx, "bdpt", is);
  const test::ImageStats ref = test::estimateImage(*bdpt, 24, 24, 777, 24 * 24 * 1024, 3, 3);
  for (const std::string m : {"pssmlt", "pssmlt-bdpt", "mmlt"}) {
    RenderSettings s;
    s.directLight = DirectLight::Chains;  // chains over every length (the automatic choice: direct_light_rule_test)
    s.method = m;
    s.width = s.height = 24;
    s.integrator = is;
    s.mutationsPerPixel = m == "pssmlt-bdpt" ? 16 : 32;
    s.bootstrapSamples = 40000;
    s.chains = 16;
    const test::ImageStats st = test::markovChainStats(*sp, s, 24, 24, 12, 3);
    int where = 0;
    const double z = test::maxZ(st, ref, &where);
    std::printf("%-12s pbrt twin %.5f +- %.5f  bdpt on the Mitsuba twin %.5f +- %.5f  max z %.2f\n", m.c_str(),
                st.mean[0], st.stdErr[0], ref.mean[0], ref.stdErr[0], z);
    EXPECT_LT(z, 5.0) << m << " entry " << where << ": " << st.mean[where] << " +- " << st.stdErr[where] << " vs "
                      << ref.mean[where] << " +- " << ref.stdErr[where];
    EXPECT_LT(5 * std::hypot(st.stdErr[0], ref.stdErr[0]), 0.10 * ref.mean[0]) << m << ": test too weak";
  }
}

}  // namespace
}  // namespace mlt
