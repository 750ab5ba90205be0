#include "common/scene/mesh_utils.h"

#include <cmath>
#include <stdexcept>

namespace mlt {

MeshDesc makeRectangle() {
  MeshDesc m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.indices = {0, 1, 2, 2, 3, 0};
  return m;
}

MeshDesc makeCube() {
  MeshDesc m;
  // For each face: the outward normal axis/sign; corners ordered counter-clockwise seen from outside.
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign = -1; sign <= 1; sign += 2) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      // (u, v, axis) is right-handed, so counter-clockwise in (u, v) faces +axis; swap for -axis.
      const float cu[4] = {-1, 1, 1, -1}, cv[4] = {-1, -1, 1, 1};
      const uint32_t base = uint32_t(m.positions.size());
      for (int c = 0; c < 4; ++c) {
        Vec3 p;
        p[axis] = float(sign);
        p[u] = cu[c];
        p[v] = cv[c];
        m.positions.push_back(p);
        m.uvs.push_back({0.5f * (cu[c] + 1), 0.5f * (cv[c] + 1)});
      }
      if (sign > 0) m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base + 2, base + 3, base});
      else m.indices.insert(m.indices.end(), {base, base + 2, base + 1, base + 2, base, base + 3});
    }
  }
  return m;
}

MeshDesc makeDisk(int segments) {
  MeshDesc m;
  m.positions.push_back({0, 0, 0});
  m.uvs.push_back({0, 0});
  for (int i = 0; i <= segments; ++i) {
    const double phi = 2.0 * M_PI * i / segments;
    m.positions.push_back({float(std::cos(phi)), float(std::sin(phi)), 0});
    m.uvs.push_back({1.0f, float(i) / segments});
  }
  for (int i = 0; i < segments; ++i) m.indices.insert(m.indices.end(), {0u, uint32_t(i + 1), uint32_t(i + 2)});
  return m;
}

MeshDesc makeSphere(int nTheta, int nPhi) {
  MeshDesc m;
  for (int i = 0; i <= nTheta; ++i) {
    const double theta = M_PI * i / nTheta;
    for (int j = 0; j <= nPhi; ++j) {
      const double phi = 2.0 * M_PI * j / nPhi;
      Vec3 p(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
      if (i == 0) p = {0, 0, 1};
      if (i == nTheta) p = {0, 0, -1};
      m.positions.push_back(p);
      m.normals.push_back(p);
      m.uvs.push_back({float(j) / nPhi, float(i) / nTheta});
    }
  }
  auto idx = [&](int i, int j) { return uint32_t(i * (nPhi + 1) + j); };
  for (int i = 0; i < nTheta; ++i)
    for (int j = 0; j < nPhi; ++j) {
      // Seen from outside, (theta, phi) increasing is clockwise (theta grows downward): wind accordingly.
      const uint32_t a = idx(i, j), b = idx(i + 1, j), c = idx(i + 1, j + 1), d = idx(i, j + 1);
      if (i != 0) m.indices.insert(m.indices.end(), {a, b, d});
      if (i != nTheta - 1) m.indices.insert(m.indices.end(), {b, c, d});
    }
  return m;
}

void transformMesh(MeshDesc& mesh, const Transform& toWorld, bool keepOrientation) {
  for (Vec3& p : mesh.positions) p = toWorld.point(p);
  if (!mesh.normals.empty()) {
    const Transform invT = toWorld.inverse().transpose();
    for (Vec3& n : mesh.normals) {
      const Vec3 t = invT.vector(n);
      const float len = length(t);
      n = len > 0 ? t / len : t;
    }
  }
  if (keepOrientation && toWorld.determinant3x3() < 0)
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
}

void flipMesh(MeshDesc& mesh) {
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
  for (Vec3& n : mesh.normals) n = -n;
}

void computeSmoothNormals(MeshDesc& mesh) {
  std::vector<Vec3> acc(mesh.positions.size(), Vec3(0.0f));
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t i[3] = {mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]};
    const Vec3 p[3] = {mesh.positions[i[0]], mesh.positions[i[1]], mesh.positions[i[2]]};
    const Vec3 n = cross(p[1] - p[0], p[2] - p[0]);
    const float len = length(n);
    if (!(len > 0)) continue;
    const Vec3 fn = n / len;
    for (int k = 0; k < 3; ++k) {
      const Vec3 e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
      const float l1 = length(e1), l2 = length(e2);
      if (!(l1 > 0 && l2 > 0)) continue;
      const float c = std::fmax(-1.0f, std::fmin(1.0f, dot(e1, e2) / (l1 * l2)));
      acc[i[k]] += fn * std::acos(c);  // weight = the triangle's angle at this corner
    }
  }
  for (Vec3& n : acc) {
    const float len = length(n);
    n = len > 0 ? n / len : Vec3(0, 0, 1);
  }
  mesh.normals = std::move(acc);
}

bool hasPositiveArea(const MeshDesc& mesh) {
  double total = 0;  // the area light's sum (area_light.cpp)
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
    const uint32_t a = mesh.indices[i], b = mesh.indices[i + 1], c = mesh.indices[i + 2];
    if (a >= mesh.positions.size() || b >= mesh.positions.size() || c >= mesh.positions.size()) return false;
    total += 0.5 * double(length(cross(mesh.positions[b] - mesh.positions[a], mesh.positions[c] - mesh.positions[a])));
  }
  return total > 0 && std::isfinite(total);
}

void validateMesh(const MeshDesc& mesh) {
  if (mesh.indices.size() % 3 != 0) throw std::runtime_error("index count is not a multiple of 3");
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
    throw std::runtime_error("normal count differs from vertex count");
  if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
    throw std::runtime_error("uv count differs from vertex count");
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (!isFinite(mesh.positions[i])) throw std::runtime_error("vertex " + std::to_string(i) + " is not finite");
  for (size_t i = 0; i < mesh.normals.size(); ++i)
    if (!isFinite(mesh.normals[i])) throw std::runtime_error("normal " + std::to_string(i) + " is not finite");
  for (size_t i = 0; i < mesh.uvs.size(); ++i)
    if (!std::isfinite(mesh.uvs[i].x) || !std::isfinite(mesh.uvs[i].y))
      throw std::runtime_error("uv " + std::to_string(i) + " is not finite");
  for (size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= mesh.positions.size())
      throw std::runtime_error("triangle " + std::to_string(i / 3) + " uses vertex " + std::to_string(mesh.indices[i]) +
                               " but there are only " + std::to_string(mesh.positions.size()) + " vertices");
}

}  // namespace mlt
