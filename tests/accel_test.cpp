// The Embree wrapper: exact hits on known triangles (t, p, ng winding, interpolated ns and uv, mesh and
// primitive ids), misses, ray interval handling, occluded() agreeing with intersect() on random rays in a
// closed box, bounds and input validation.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/core/rng.h"
#include "common/core/sampling.h"
#include "common/render/accel.h"
#include "common/render/render_scene.h"

namespace mlt {
namespace {

// Unit square [0,1]^2 at height z, facing +z (counter-clockwise seen from above), with uvs = (x, y).
MeshDesc quad(float z, bool withUv = true) {
  MeshDesc m;
  m.name = "quad";
  m.positions = {{0, 0, z}, {1, 0, z}, {1, 1, z}, {0, 1, z}};
  m.indices = {0, 1, 2, 0, 2, 3};
  if (withUv) m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  return m;
}

// Closed box [-1,1]^3 made of 6 quads (12 triangles), normals pointing inward.
MeshDesc box() {
  MeshDesc m;
  m.name = "box";
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 2; ++y)
      for (int z = 0; z < 2; ++z) m.positions.push_back(Vec3(x ? 1.f : -1.f, y ? 1.f : -1.f, z ? 1.f : -1.f));
  auto idx = [](int x, int y, int z) { return uint32_t(4 * x + 2 * y + z); };
  auto face = [&](uint32_t a, uint32_t b, uint32_t c, uint32_t d) { m.indices.insert(m.indices.end(), {a, b, c, a, c, d}); };
  face(idx(0, 0, 0), idx(1, 0, 0), idx(1, 1, 0), idx(0, 1, 0));  // z = -1
  face(idx(0, 0, 1), idx(0, 1, 1), idx(1, 1, 1), idx(1, 0, 1));  // z = +1
  face(idx(0, 0, 0), idx(0, 0, 1), idx(1, 0, 1), idx(1, 0, 0));  // y = -1
  face(idx(0, 1, 0), idx(1, 1, 0), idx(1, 1, 1), idx(0, 1, 1));  // y = +1
  face(idx(0, 0, 0), idx(0, 1, 0), idx(0, 1, 1), idx(0, 0, 1));  // x = -1
  face(idx(1, 0, 0), idx(1, 0, 1), idx(1, 1, 1), idx(1, 1, 0));  // x = +1
  return m;
}

// Geometric normals are computed once per triangle at build: after an empty mesh (an unused id) the next
// mesh's hits still carry their own triangle's normal, the cross product of its edges normalized, for
// triangles of every orientation.
TEST(Accel, FaceNormalsBelongToTheHitTriangleAfterAnEmptyMesh) {
  MeshDesc empty;
  empty.name = "empty";
  MeshDesc tilted;
  tilted.name = "tilted";
  Pcg32 rng(5, 9);
  for (int f = 0; f < 16; ++f) {  // small random triangles around points of a sphere of radius 3
    const Vec3 c = sampleUniformSphere({rng.uniform(), rng.uniform()}) * 3.0f;
    for (int k = 0; k < 3; ++k)
      tilted.positions.push_back(c + Vec3(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f) * 0.4f);
    tilted.indices.insert(tilted.indices.end(), {uint32_t(3 * f), uint32_t(3 * f + 1), uint32_t(3 * f + 2)});
  }
  Accel accel({empty, quad(-10.0f), tilted});
  int hits = 0;
  for (int f = 0; f < 16; ++f) {
    const Vec3 p0 = tilted.positions[3 * f], p1 = tilted.positions[3 * f + 1], p2 = tilted.positions[3 * f + 2];
    Ray r;
    r.o = {0, 0, 0};
    r.d = normalize((p0 + p1 + p2) / 3.0f);  // the triangle's centroid, from the centre
    const std::optional<SurfaceHit> h = accel.intersect(r);
    ASSERT_TRUE(h) << "triangle " << f;
    ASSERT_EQ(h->meshId, 2u);
    const uint32_t g = h->primId;  // maybe another triangle in front of this one: check the one hit
    const Vec3 a = tilted.positions[3 * g], b = tilted.positions[3 * g + 1], c = tilted.positions[3 * g + 2];
    const Vec3 want = normalize(cross(b - a, c - a));
    EXPECT_EQ(h->ng.x, want.x) << "triangle " << g;
    EXPECT_EQ(h->ng.y, want.y) << "triangle " << g;
    EXPECT_EQ(h->ng.z, want.z) << "triangle " << g;
    hits += g == uint32_t(f);
  }
  EXPECT_GE(hits, 8);
}

TEST(Accel, HitOnQuadIsExact) {
  Accel accel({quad(2.0f)});
  Ray r;
  r.o = {0.25f, 0.75f, 0};
  r.d = {0, 0, 1};
  auto h = accel.intersect(r);
  ASSERT_TRUE(h);
  EXPECT_FLOAT_EQ(h->t, 2.0f);
  EXPECT_FLOAT_EQ(h->p.x, 0.25f);
  EXPECT_FLOAT_EQ(h->p.y, 0.75f);
  EXPECT_FLOAT_EQ(h->p.z, 2.0f);
  EXPECT_FLOAT_EQ(h->ng.z, 1.0f);  // counter-clockwise seen from +z
  EXPECT_FLOAT_EQ(h->ns.z, 1.0f);
  EXPECT_NEAR(h->uv.x, 0.25f, 1e-6f);
  EXPECT_NEAR(h->uv.y, 0.75f, 1e-6f);
  EXPECT_EQ(h->meshId, 0u);
  EXPECT_EQ(h->primId, 1u);  // upper-left triangle (0, 2, 3)
  EXPECT_EQ(h->bsdf, -1);
  EXPECT_EQ(h->light, -1);

  // The same from above: ng does not depend on the ray direction.
  r.o = {0.75f, 0.25f, 5};
  r.d = normalize(Vec3(0, 0, -1));
  h = accel.intersect(r);
  ASSERT_TRUE(h);
  EXPECT_FLOAT_EQ(h->t, 3.0f);
  EXPECT_FLOAT_EQ(h->ng.z, 1.0f);
  EXPECT_EQ(h->primId, 0u);
  EXPECT_NEAR(h->uv.x, 0.75f, 1e-6f);
  EXPECT_NEAR(h->uv.y, 0.25f, 1e-6f);
}

TEST(Accel, ObliqueRayAndBarycentricUvWithoutTexcoords) {
  MeshDesc tri;
  tri.name = "tri";
  tri.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
  tri.indices = {0, 1, 2};
  Accel accel({tri});
  const Vec3 target(0.5f, 0.3f, 0);
  Ray r;
  r.o = {3, -1, 4};
  r.d = normalize(target - r.o);
  auto h = accel.intersect(r);
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->t, distance(r.o, target), 1e-5f);
  EXPECT_NEAR(distance(h->p, target), 0.0f, 1e-5f);
  // No uvs: Embree's barycentrics with p = (1-u-v) p0 + u p1 + v p2.
  EXPECT_NEAR(h->uv.x, 0.25f, 1e-5f);
  EXPECT_NEAR(h->uv.y, 0.15f, 1e-5f);
}

TEST(Accel, ShadingNormalInterpolatedAndOnGeometricSide) {
  MeshDesc tri;
  tri.name = "tri";
  tri.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  tri.indices = {0, 1, 2};
  tri.normals = {normalize(Vec3(1, 0, 1)), normalize(Vec3(0, 1, 1)), Vec3(0, 0, 1)};
  Ray r;
  r.o = {0.2f, 0.5f, 1};
  r.d = {0, 0, -1};
  {
    Accel accel({tri});
    auto h = accel.intersect(r);
    ASSERT_TRUE(h);
    const Vec3 expected = normalize(tri.normals[0] * 0.3f + tri.normals[1] * 0.2f + tri.normals[2] * 0.5f);
    EXPECT_NEAR(dot(h->ns, expected), 1.0f, 1e-6f);
    EXPECT_NEAR(length(h->ns), 1.0f, 1e-6f);
  }
  // Vertex normals on the back side get flipped to ng's side.
  for (Vec3& n : tri.normals) n = -n;
  Accel accel({tri});
  auto h = accel.intersect(r);
  ASSERT_TRUE(h);
  EXPECT_GT(dot(h->ns, h->ng), 0.0f);
  EXPECT_FLOAT_EQ(h->ng.z, 1.0f);
}

TEST(Accel, MissesAndRayInterval) {
  Accel accel({quad(2.0f)});
  Ray r;
  r.o = {1.5f, 0.5f, 0};
  r.d = {0, 0, 1};
  EXPECT_FALSE(accel.intersect(r));  // beside the quad
  EXPECT_FALSE(accel.occluded(r));
  r.o = {0.5f, 0.5f, 0};
  r.d = {0, 0, -1};
  EXPECT_FALSE(accel.intersect(r));  // pointing away
  r.d = {0, 0, 1};
  r.tMax = 1.9f;
  EXPECT_FALSE(accel.intersect(r));  // ends before the quad
  EXPECT_FALSE(accel.occluded(r));
  r.tMax = 2.1f;
  EXPECT_TRUE(accel.intersect(r));
  EXPECT_TRUE(accel.occluded(r));
  r.tMin = 2.05f;
  r.tMax = 10;
  EXPECT_FALSE(accel.intersect(r));  // starts after it
}

TEST(Accel, GeometryIdIsMeshIndexAndClosestHitWins) {
  MeshDesc empty;
  empty.name = "empty";
  Accel accel({quad(3.0f), empty, quad(1.0f)});
  Ray r;
  r.o = {0.5f, 0.5f, 0};
  r.d = {0, 0, 1};
  auto h = accel.intersect(r);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->meshId, 2u);
  EXPECT_FLOAT_EQ(h->t, 1.0f);
  r.tMin = 1.5f;
  h = accel.intersect(r);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->meshId, 0u);
  EXPECT_FLOAT_EQ(accel.bounds().lo.z, 1.0f);
  EXPECT_FLOAT_EQ(accel.bounds().hi.z, 3.0f);
  EXPECT_FLOAT_EQ(accel.bounds().hi.x, 1.0f);
}

TEST(Accel, OccludedAgreesWithIntersectInBox) {
  Accel accel({box(), quad(0.2f)});
  Pcg32 rng(42, 7);
  int hits = 0, blocked = 0;
  for (int i = 0; i < 20000; ++i) {
    Ray r;
    r.o = Vec3(rng.uniform() * 1.8f - 0.9f, rng.uniform() * 1.8f - 0.9f, rng.uniform() * 1.8f - 0.9f);
    r.d = sampleUniformSphere(rng.uniform2());
    r.tMax = rng.uniform() * 3.0f;
    auto h = accel.intersect(r);
    const bool occ = accel.occluded(r);
    ASSERT_EQ(bool(h), occ) << "ray " << i;
    if (h) {
      ++blocked;
      EXPECT_LE(h->t, r.tMax);
      EXPECT_NEAR(length(h->ng), 1.0f, 1e-5f);
      // The box's faces point inward, so from inside ng faces the ray origin; the quad is two-facing.
      if (h->meshId == 0) {
        EXPECT_LT(dot(h->ng, r.d), 0.0f);
        EXPECT_NEAR(std::fmax(std::fabs(h->p.x), std::fmax(std::fabs(h->p.y), std::fabs(h->p.z))), 1.0f, 1e-4f);
      }
    }
    r.tMax = std::numeric_limits<float>::infinity();
    if (accel.intersect(r)) ++hits;
  }
  EXPECT_EQ(hits, 20000);  // the box is closed: every unbounded ray from inside hits
  EXPECT_GT(blocked, 1000);
  EXPECT_LT(blocked, 19000);
}

TEST(Accel, RejectsBadIndices) {
  MeshDesc m = quad(0);
  m.indices.push_back(0);
  EXPECT_THROW(Accel{std::vector<MeshDesc>{m}}, std::runtime_error);
  m = quad(0);
  m.indices[4] = 9;
  EXPECT_THROW(Accel{std::vector<MeshDesc>{m}}, std::runtime_error);
  m = quad(0);
  m.normals = {{0, 0, 1}};
  EXPECT_THROW(Accel{std::vector<MeshDesc>{m}}, std::runtime_error);
}

// ---- RenderScene ----------------------------------------------------------------------------------
// The box [-1,1]^3 (inward normals), an emitting quad under its ceiling facing down, a point light and a
// constant environment.
SceneDesc boxScene() {
  SceneDesc d;
  d.sourceFile = "test";
  d.bsdfs.resize(2);
  d.bsdfs[0].id = "white";
  d.bsdfs[1].id = "lamp";
  d.meshes.push_back(box());
  d.meshes[0].bsdf = 0;
  MeshDesc lamp;
  lamp.name = "lamp";
  lamp.positions = {{-0.2f, 0.9f, -0.2f}, {0.2f, 0.9f, -0.2f}, {0.2f, 0.9f, 0.2f}, {-0.2f, 0.9f, 0.2f}};
  lamp.indices = {0, 1, 2, 0, 2, 3};  // normal -y: facing down into the box
  lamp.bsdf = 1;
  lamp.emission = Color(5);
  d.meshes.push_back(lamp);
  LightDesc point;
  point.position = {0.5f, 0.5f, 0.5f};
  d.lights.push_back(point);
  LightDesc env;
  env.type = LightDesc::Type::Constant;
  d.lights.push_back(env);
  d.camera.toWorld = Transform::lookAt({0, 0, 0.9f}, {0, 0, 0}, {0, 1, 0});
  d.camera.width = d.camera.height = 16;
  return d;
}

TEST(RenderScene, BuildsLightsAndFillsHitIndices) {
  const auto scene = RenderScene::build(boxScene());
  ASSERT_EQ(scene->lights().size(), 3u);  // point, constant, then the area light of mesh 1
  EXPECT_TRUE(scene->light(0).deltaPosition());
  ASSERT_EQ(scene->infiniteLights().size(), 1u);
  EXPECT_EQ(scene->infiniteLights()[0], 1);
  EXPECT_EQ(scene->lightSampler().size(), 3u);
  EXPECT_NEAR(scene->radius(), std::sqrt(3.0f), 1e-5f);
  EXPECT_NEAR(length(scene->center()), 0.0f, 1e-6f);
  EXPECT_EQ(scene->camera().width(), 16);

  Ray up;
  up.o = {0, 0, 0};
  up.d = {0, 1, 0};
  auto h = scene->intersect(up);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->meshId, 1u);
  EXPECT_EQ(h->bsdf, 1);
  EXPECT_EQ(h->light, 2);
  EXPECT_FLOAT_EQ(h->t, 0.9f);
  EXPECT_EQ(scene->light(h->light).L(h->p, h->ng, h->uv, -up.d).r, 5.0f);  // seen from below: front side
  Ray down = up;
  down.d = {0, -1, 0};
  h = scene->intersect(down);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->meshId, 0u);
  EXPECT_EQ(h->bsdf, 0);
  EXPECT_EQ(h->light, -1);
}

TEST(RenderScene, VisibilityWithOffsetsAndBlockers) {
  const auto scene = RenderScene::build(boxScene());
  const Vec3 floorP(0.1f, -1, 0.1f), floorN(0, 1, 0);
  const Vec3 wallP(-1, -0.99f, 0.3f), wallN(1, 0, 0);  // near the floor-wall edge
  EXPECT_TRUE(scene->visible(floorP, floorN, wallP, wallN));
  EXPECT_TRUE(scene->visible(wallP, wallN, floorP, floorN));
  // The lamp blocks the ceiling above it; a point light (zero normal) sees the floor.
  EXPECT_FALSE(scene->visible(floorP, floorN, {0, 1, 0}, {0, -1, 0}));
  EXPECT_TRUE(scene->visible(floorP, floorN, {0.5f, 0.5f, 0.5f}, {}));
  // A point on the lamp's underside sees the floor.
  EXPECT_TRUE(scene->visible({0, 0.9f, 0}, {0, -1, 0}, floorP, floorN));
  // Random pairs of floor and wall points: all mutually visible (no self-intersection from offsets).
  Pcg32 rng(3, 3);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 a(rng.uniform() * 2 - 1, -1, rng.uniform() * 2 - 1);
    const Vec3 b(1, rng.uniform() * 2 - 1, rng.uniform() * 2 - 1);
    ASSERT_TRUE(scene->visible(a, floorN, b, {-1, 0, 0})) << i;
  }
}

TEST(RenderScene, RejectsInvalidScenes) {
  auto expectError = [](const SceneDesc& d, const std::string& fragment) {
    try {
      RenderScene::build(d);
      ADD_FAILURE() << "no error, expected: " << fragment;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  SceneDesc d = boxScene();
  d.lights.clear();
  d.meshes[1].emission.reset();
  expectError(d, "scene has no emitters");
  d = boxScene();
  d.meshes[0].bsdf = 2;
  expectError(d, "bsdf index 2 out of range");
  d = boxScene();
  d.meshes[1].positions[2].y = std::numeric_limits<float>::quiet_NaN();
  expectError(d, "non-finite position");
  d = boxScene();
  d.camera.width = 0;
  expectError(d, "width/height");
  d = boxScene();
  d.meshes[1].indices[5] = 17;
  expectError(d, "out of range");
}

}  // namespace
}  // namespace mlt
