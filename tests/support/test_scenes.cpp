// Scene descriptions for tests (see test_scenes.h).
#include "tests/support/test_scenes.h"

#include <cmath>
#include <string>

namespace mlt::test {

namespace {

int addDiffuse(SceneDesc& scene, Color rho, const std::string& id) {
  BsdfDesc b;
  b.type = BsdfDesc::Type::Diffuse;
  b.id = id;
  b.reflectance.type = TextureDesc::Type::Constant;
  b.reflectance.value = rho;
  scene.bsdfs.push_back(b);
  return int(scene.bsdfs.size()) - 1;
}

// Quad p0 p1 p2 p3 (in order around its boundary) with its front side toward `inside`.
void addQuad(MeshDesc& m, Vec3 p0, Vec3 p1, Vec3 p2, Vec3 p3, const Vec3& inside) {
  const Vec3 n = cross(p1 - p0, p2 - p0);
  if (dot(n, inside - p0) < 0) std::swap(p1, p3);
  const uint32_t b = uint32_t(m.positions.size());
  m.positions.insert(m.positions.end(), {p0, p1, p2, p3});
  m.indices.insert(m.indices.end(), {b, b + 1, b + 2, b, b + 2, b + 3});
}

MeshDesc quadMesh(const std::string& name, int bsdf, Vec3 p0, Vec3 p1, Vec3 p2, Vec3 p3, const Vec3& inside) {
  MeshDesc m;
  m.name = name;
  m.bsdf = bsdf;
  addQuad(m, p0, p1, p2, p3, inside);
  return m;
}

// Axis-aligned box rotated by `angle` radians about y, faces pointing outward.
MeshDesc boxMesh(const std::string& name, int bsdf, const Vec3& center, const Vec3& half, float angle) {
  MeshDesc m;
  m.name = name;
  m.bsdf = bsdf;
  const float c = std::cos(angle), s = std::sin(angle);
  auto P = [&](float x, float y, float z) {
    const Vec3 l(x * half.x, y * half.y, z * half.z);
    return center + Vec3(c * l.x + s * l.z, l.y, -s * l.x + c * l.z);
  };
  auto face = [&](Vec3 a, Vec3 b, Vec3 cc, Vec3 d) {
    const Vec3 faceCenter = (a + b + cc + d) * 0.25f;
    addQuad(m, a, b, cc, d, faceCenter + (faceCenter - center));  // front away from the center
  };
  face(P(-1, -1, -1), P(1, -1, -1), P(1, 1, -1), P(-1, 1, -1));
  face(P(-1, -1, 1), P(1, -1, 1), P(1, 1, 1), P(-1, 1, 1));
  face(P(-1, -1, -1), P(-1, 1, -1), P(-1, 1, 1), P(-1, -1, 1));
  face(P(1, -1, -1), P(1, 1, -1), P(1, 1, 1), P(1, -1, 1));
  face(P(-1, -1, -1), P(1, -1, -1), P(1, -1, 1), P(-1, -1, 1));
  face(P(-1, 1, -1), P(1, 1, -1), P(1, 1, 1), P(-1, 1, 1));
  return m;
}

// UV sphere: `rings` latitude bands x 2 rings longitude segments; inward: front side toward the center.
MeshDesc sphereMesh(const std::string& name, int bsdf, const Vec3& center, float radius, int rings, bool inward,
                    bool smoothNormals) {
  MeshDesc m;
  m.name = name;
  m.bsdf = bsdf;
  const int segs = 2 * rings;
  for (int i = 0; i <= rings; ++i) {
    const float theta = kPi * float(i) / float(rings);
    for (int j = 0; j <= segs; ++j) {
      const float phi = 2 * kPi * float(j) / float(segs);
      const Vec3 n(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
      m.positions.push_back(center + n * radius);
      if (smoothNormals) m.normals.push_back(inward ? -n : n);
    }
  }
  for (int i = 0; i < rings; ++i) {
    for (int j = 0; j < segs; ++j) {
      const uint32_t a = uint32_t(i * (segs + 1) + j), b = a + 1, c = a + uint32_t(segs + 1), d = c + 1;
      // Winding (a, b, c) has its normal pointing outward for this parameterization; check and flip.
      uint32_t tri[2][3] = {{a, c, b}, {b, c, d}};
      for (auto& t : tri) {
        const Vec3 p0 = m.positions[t[0]], p1 = m.positions[t[1]], p2 = m.positions[t[2]];
        const Vec3 nrm = cross(p1 - p0, p2 - p0);
        if (lengthSquared(nrm) == 0) continue;  // degenerate at the poles
        const bool outward = dot(nrm, (p0 + p1 + p2) * (1.0f / 3) - center) > 0;
        if (outward == inward) std::swap(t[1], t[2]);
        m.indices.insert(m.indices.end(), {t[0], t[1], t[2]});
      }
    }
  }
  return m;
}

CameraDesc pinhole(const Vec3& origin, const Vec3& target, const Vec3& up, float fovDeg, int width, int height) {
  CameraDesc c;
  c.type = CameraDesc::Type::Perspective;
  c.toWorld = Transform::lookAt(origin, target, up);
  c.fovDeg = fovDeg;
  c.fovAxis = CameraDesc::FovAxis::X;
  c.nearClip = 1e-3f;
  c.width = width;
  c.height = height;
  return c;
}

// The walls of the box; the light (if any) is added by the caller.
SceneDesc cornellShell(int width, int height) {
  SceneDesc s;
  s.sourceFile = "<test scene>";
  s.camera = pinhole(Vec3(0, 0, -3.6f), Vec3(0, 0, 0), Vec3(0, 1, 0), 45.0f, width, height);
  const int white = addDiffuse(s, Color(0.73f), "white");
  const int red = addDiffuse(s, Color(0.63f, 0.065f, 0.05f), "red");
  const int green = addDiffuse(s, Color(0.14f, 0.45f, 0.091f), "green");
  const Vec3 inside(0, 0, 0);
  s.meshes.push_back(quadMesh("floor", white, {-1, -1, -1}, {1, -1, -1}, {1, -1, 1}, {-1, -1, 1}, inside));
  s.meshes.push_back(quadMesh("ceiling", white, {-1, 1, -1}, {1, 1, -1}, {1, 1, 1}, {-1, 1, 1}, inside));
  s.meshes.push_back(quadMesh("back", white, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}, inside));
  s.meshes.push_back(quadMesh("left", red, {-1, -1, -1}, {-1, 1, -1}, {-1, 1, 1}, {-1, -1, 1}, inside));
  s.meshes.push_back(quadMesh("right", green, {1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}, inside));
  return s;
}

void addCeilingLight(SceneDesc& s, Color Le) {
  const int black = addDiffuse(s, Color(0.0f), "light");
  const float h = 0.25f, y = 0.99f;
  MeshDesc light = quadMesh("light", black, {-h, y, -h}, {h, y, -h}, {h, y, h}, {-h, y, h}, Vec3(0, 0, 0));
  light.emission = Le;
  s.meshes.push_back(light);
}

}  // namespace

SceneDesc furnaceSphere(float Le, float rho, int res, int width, int height) {
  SceneDesc s;
  s.sourceFile = "<furnace sphere>";
  s.camera = pinhole(Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 0), 90.0f, width, height);
  const int b = addDiffuse(s, Color(rho), "furnace");
  MeshDesc m = sphereMesh("furnace sphere", b, Vec3(0, 0, 0), 1.0f, res, /*inward=*/true, /*smooth=*/false);
  m.emission = Color(Le);
  s.meshes.push_back(m);
  return s;
}

double furnaceRadiance(double Le, double rho, int maxDepth) {
  if (maxDepth < 0) return Le / (1 - rho);
  double sum = 0, term = 1;
  for (int i = 0; i < maxDepth; ++i, term *= rho) sum += term;
  return Le * sum;
}

SceneDesc cornellBoxSphereLight(int width, int height) {
  SceneDesc s = cornellShell(width, height);
  s.meshes.push_back(boxMesh("block", 0, Vec3(0.35f, -0.6f, 0.3f), Vec3(0.3f, 0.4f, 0.3f), 0.3f));
  const int black = addDiffuse(s, Color(0.0f), "light");
  MeshDesc light = sphereMesh("sphere light", black, Vec3(-0.3f, 0.55f, 0.2f), 0.15f, 16, false, true);
  light.emission = Color(40.0f);
  light.convex = true;
  s.meshes.push_back(light);
  return s;
}

SceneDesc smallCornellBox(int width, int height, Color Le) {
  SceneDesc s = cornellShell(width, height);
  s.meshes.push_back(boxMesh("block", 0, Vec3(0.35f, -0.6f, 0.3f), Vec3(0.3f, 0.4f, 0.3f), 0.3f));
  addCeilingLight(s, Le);
  return s;
}

namespace {

void addSpecularSpheres(SceneDesc& s, bool smoothNormals) {
  BsdfDesc glass;
  glass.type = BsdfDesc::Type::Dielectric;
  glass.id = "glass";
  glass.intIOR = 1.5f;
  glass.extIOR = 1.0f;
  s.bsdfs.push_back(glass);
  const int glassId = int(s.bsdfs.size()) - 1;
  BsdfDesc mirror;
  mirror.type = BsdfDesc::Type::Conductor;
  mirror.id = "mirror";
  mirror.mirror = true;
  s.bsdfs.push_back(mirror);
  const int mirrorId = int(s.bsdfs.size()) - 1;
  s.meshes.push_back(sphereMesh("glass sphere", glassId, Vec3(0.45f, -0.65f, -0.2f), 0.35f, 16, false, smoothNormals));
  s.meshes.push_back(sphereMesh("mirror sphere", mirrorId, Vec3(-0.45f, -0.65f, 0.4f), 0.35f, 16, false, smoothNormals));
}

void addPointAndSpot(SceneDesc& s) {
  LightDesc point;
  point.type = LightDesc::Type::Point;
  point.intensity = Color(2.0f);
  point.position = Vec3(-0.3f, 0.8f, 0.0f);
  s.lights.push_back(point);
  LightDesc spot;
  spot.type = LightDesc::Type::Spot;
  spot.intensity = Color(6.0f);
  spot.position = Vec3(0.5f, 0.9f, -0.5f);
  spot.direction = normalize(Vec3(-0.3f, -1.0f, 0.6f));
  spot.cutoffAngleDeg = 35;
  spot.beamWidthDeg = 25;
  s.lights.push_back(spot);
}

}  // namespace

SceneDesc cornellBoxSpecular(int width, int height, bool smoothNormals) {
  SceneDesc s = cornellShell(width, height);
  addSpecularSpheres(s, smoothNormals);
  addCeilingLight(s, Color(10.0f));
  return s;
}

SceneDesc cornellBoxPointSpot(int width, int height) {
  SceneDesc s = cornellShell(width, height);
  s.meshes.push_back(boxMesh("block", 0, Vec3(0.35f, -0.6f, 0.3f), Vec3(0.3f, 0.4f, 0.3f), 0.3f));
  addPointAndSpot(s);
  return s;
}

SceneDesc cornellBoxSpecularPointSpot(int width, int height) {
  SceneDesc s = cornellShell(width, height);
  addSpecularSpheres(s, /*smoothNormals=*/true);
  addPointAndSpot(s);
  return s;
}

SceneDesc twoLightsReflector(int width, int height) {
  SceneDesc s = cornellShell(width, height);
  s.meshes.push_back(boxMesh("block", 0, Vec3(0.35f, -0.6f, 0.3f), Vec3(0.3f, 0.4f, 0.3f), 0.3f));
  const int black = addDiffuse(s, Color(0.0f), "light");
  const float H = 0.8f, y = 0.99f;
  MeshDesc panel = quadMesh("panel", black, {-H, y, -H}, {H, y, -H}, {H, y, H}, {-H, y, H}, Vec3(0, 0, 0));
  panel.emission = Color(0.5f);
  s.meshes.push_back(panel);
  // The small light faces down at (cx, yl, cz); the cup's mirror walls reach 0.15 below it.
  const float cx = -0.7f, cz = 0.6f, yl = 0.97f, h = 0.04f, r = 0.08f, depth = 0.15f;
  MeshDesc bulb = quadMesh("bulb", black, {cx - h, yl, cz - h}, {cx + h, yl, cz - h}, {cx + h, yl, cz + h},
                           {cx - h, yl, cz + h}, Vec3(cx, 0, cz));
  bulb.emission = Color(400.0f);
  s.meshes.push_back(bulb);
  BsdfDesc mirror;
  mirror.type = BsdfDesc::Type::Conductor;
  mirror.id = "reflector";
  mirror.mirror = true;
  s.bsdfs.push_back(mirror);
  const int mirrorId = int(s.bsdfs.size()) - 1;
  MeshDesc cup;
  cup.name = "reflector";
  cup.bsdf = mirrorId;
  const Vec3 inside(cx, yl - depth / 2, cz);
  const float y0 = yl + 0.005f, y1 = yl - depth;
  addQuad(cup, {cx - r, y0, cz - r}, {cx + r, y0, cz - r}, {cx + r, y1, cz - r}, {cx - r, y1, cz - r}, inside);
  addQuad(cup, {cx - r, y0, cz + r}, {cx + r, y0, cz + r}, {cx + r, y1, cz + r}, {cx - r, y1, cz + r}, inside);
  addQuad(cup, {cx - r, y0, cz - r}, {cx - r, y0, cz + r}, {cx - r, y1, cz + r}, {cx - r, y1, cz - r}, inside);
  addQuad(cup, {cx + r, y0, cz - r}, {cx + r, y0, cz + r}, {cx + r, y1, cz + r}, {cx + r, y1, cz - r}, inside);
  s.meshes.push_back(cup);
  return s;
}

}  // namespace mlt::test
