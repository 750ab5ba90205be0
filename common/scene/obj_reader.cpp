// Wavefront OBJ through tinyobjloader. Vertices are de-indexed per unique (position, normal, uv) triple.
#include <fstream>
#include <map>
#include <tuple>

#include <tiny_obj_loader.h>

#include "common/scene/mesh_readers.h"
#include "common/scene/scene_error.h"

namespace mlt {

MeshDesc readObj(const std::string& path, bool flipTexCoords) {
  std::ifstream in(path);
  if (!in) throw SceneError(path, 0, "cannot open OBJ file");
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  // No material reader: mtllib lines are ignored (materials come from the scene file).
  const bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, nullptr, /*triangulate=*/true);
  if (!ok) throw SceneError(path, 0, "cannot parse OBJ file: " + err);
  if (!err.empty()) throw SceneError(path, 0, "OBJ file: " + err);

  bool allNormals = true, allUvs = true;
  size_t corners = 0;
  for (const auto& s : shapes) {
    for (size_t f = 0; f < s.mesh.num_face_vertices.size(); ++f)
      if (s.mesh.num_face_vertices[f] != 3)
        throw SceneError(path, 0, "OBJ face could not be triangulated (" + std::to_string(s.mesh.num_face_vertices[f]) + " corners)");
    for (const auto& idx : s.mesh.indices) {
      if (idx.normal_index < 0) allNormals = false;
      if (idx.texcoord_index < 0) allUvs = false;
      ++corners;
    }
  }
  if (corners == 0) allNormals = allUvs = false;

  MeshDesc mesh;
  mesh.name = path;
  std::map<std::tuple<int, int, int>, uint32_t> unique;
  const size_t nPos = attrib.vertices.size() / 3, nNrm = attrib.normals.size() / 3, nUv = attrib.texcoords.size() / 2;
  for (const auto& s : shapes) {
    for (const auto& idx : s.mesh.indices) {
      const int vi = idx.vertex_index, ni = allNormals ? idx.normal_index : -1, ti = allUvs ? idx.texcoord_index : -1;
      if (vi < 0 || size_t(vi) >= nPos) throw SceneError(path, 0, "OBJ face uses vertex " + std::to_string(vi + 1) + " which does not exist");
      if (ni >= 0 && size_t(ni) >= nNrm) throw SceneError(path, 0, "OBJ face uses normal " + std::to_string(ni + 1) + " which does not exist");
      if (ti >= 0 && size_t(ti) >= nUv) throw SceneError(path, 0, "OBJ face uses texture coordinate " + std::to_string(ti + 1) + " which does not exist");
      const auto key = std::make_tuple(vi, ni, ti);
      auto it = unique.find(key);
      if (it == unique.end()) {
        const uint32_t id = uint32_t(mesh.positions.size());
        mesh.positions.push_back({attrib.vertices[3 * vi], attrib.vertices[3 * vi + 1], attrib.vertices[3 * vi + 2]});
        if (ni >= 0) mesh.normals.push_back({attrib.normals[3 * ni], attrib.normals[3 * ni + 1], attrib.normals[3 * ni + 2]});
        if (ti >= 0) {
          const float v = attrib.texcoords[2 * ti + 1];
          mesh.uvs.push_back({attrib.texcoords[2 * ti], flipTexCoords ? 1.0f - v : v});
        }
        it = unique.emplace(key, id).first;
      }
      mesh.indices.push_back(it->second);
    }
  }
  return mesh;
}

}  // namespace mlt
