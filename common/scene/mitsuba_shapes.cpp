// Mitsuba shape plugins -> world-space triangle meshes. Analytic shapes keep Mitsuba's normal (the
// transformed object-space normal) even under mirroring transforms; triangle meshes take their geometric
// normal from world-space winding, as Mitsuba's meshes do.
#include <filesystem>
#include <limits>

#include "common/scene/mesh_readers.h"
#include "common/scene/mesh_utils.h"
#include "common/scene/mitsuba_internal.h"

namespace mlt::mitsuba {

void Loader::parseShape(const XmlElement& el) {
  checkAttributes(el, {"type", "id", "name"});
  const std::string type = requireAttr(el, "type");
  PropertyList props(el);
  std::vector<const XmlElement*> nested;
  collect(el, props, nested);
  const std::string where = el.file + ":" + std::to_string(el.line);

  MeshDesc mesh;
  Transform toWorld = props.optTransform("to_world").value_or(Transform());
  bool analytic = true;
  bool serializedFaceNormals = false;  // the serialized record's face-normals flag
  if (type == "obj" || type == "ply") {
    analytic = false;
    const auto file = props.optString("filename");
    if (!file) failAt(el, type + " shape needs a filename");
    const std::string path = resolveFile(*props.find("filename")->el, *file, "mesh file");
    try {
      mesh = type == "obj" ? readObj(path, props.getBool("flip_tex_coords", true)) : readPly(path);
    } catch (const SceneError& e) {
      failAt(el, std::string("cannot load mesh: ") + e.what());
    }
    mesh.name = std::filesystem::path(*file).filename().string() + " (" + where + ")";
    props.ignore({"collapse"});
  } else if (type == "serialized") {
    analytic = false;
    const auto file = props.optString("filename");
    if (!file) failAt(el, "serialized shape needs a filename");
    const std::string path = resolveFile(*props.find("filename")->el, *file, "mesh file");
    const long long index = props.getInt("shape_index", 0);
    if (index < 0 || index > std::numeric_limits<int>::max())
      props.fail(*props.find("shape_index"), "shape_index must be a non-negative integer");
    try {
      mesh = readSerialized(path, int(index), &serializedFaceNormals);
    } catch (const SceneError& e) {
      failAt(el, std::string("cannot load mesh: ") + e.what());
    }
    mesh.name = std::filesystem::path(*file).filename().string() + "#" + std::to_string(index) + " (" + where + ")";
  } else if (type == "rectangle") {
    mesh = makeRectangle();
  } else if (type == "cube") {
    mesh = makeCube();
  } else if (type == "disk") {
    mesh = makeDisk();
  } else if (type == "sphere") {
    mesh = makeSphere();
    mesh.convex = true;
    const Vec3 center = props.optVec("center").value_or(Vec3(0.0f));
    const double radius = props.getFloat("radius", 1.0);
    if (!(radius > 0)) props.fail(*props.find("radius"), "radius must be positive");
    toWorld = toWorld * Transform::translate(center) * Transform::scale(Vec3(float(radius)));
  } else {
    failAt(el, "unknown or unsupported shape type '" + type + "' (supported: obj, ply, serialized, rectangle, cube, disk, sphere)");
  }
  if (mesh.name.empty()) mesh.name = type + " at " + where;
  if (mesh.indices.empty()) failAt(el, "the mesh has no triangles");

  try {
    validateMesh(mesh);
    transformMesh(mesh, toWorld, analytic);
    validateMesh(mesh);
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    failAt(el, e.what());
  }
  const bool faceNormals = props.getBool("face_normals", false) || serializedFaceNormals;  // also on sphere: our extension
  if (faceNormals) mesh.normals.clear();
  else if (!analytic && mesh.normals.empty()) computeSmoothNormals(mesh);  // as Mitsuba does for meshes
  if (props.getBool("flip_normals", false)) flipMesh(mesh);

  // <ref name="bsdf" id=".."/> (3.x style) arrives as a named property; unnamed refs and <bsdf>s are nested.
  for (const auto& [name, p] : props.takeKind(Prop::Kind::Ref)) nested.push_back(p->el);
  for (const XmlElement* n : nested) {
    if (n->name == "bsdf" || n->name == "ref") {
      if (mesh.bsdf >= 0) failAt(*n, "the shape already has a bsdf");
      if (n->name == "ref") {
        mesh.bsdf = bsdfFromRef(*n);
      } else {
        mesh.bsdf = parseBsdf(*n);
        if (const XmlAttribute* id = n->find("id")) {
          registerId(*n, "bsdf");
          namedBsdfs_[id->value] = mesh.bsdf;
        }
      }
    } else if (n->name == "emitter") {
      if (mesh.emission) failAt(*n, "the shape already has an emitter");
      const AreaEmission e = parseAreaEmitter(*n);
      mesh.emission = e.radiance;
      mesh.emissionTexture = e.texture;
    } else {
      failAt(*n, "unsupported element inside " + describe(el));
    }
  }
  if (mesh.emission && !hasPositiveArea(mesh)) failAt(el, "an emitting shape must have a positive, finite area");
  if (mesh.bsdf < 0) {
    mesh.bsdf = defaultBsdf();
    warn(el, "shape has no bsdf; using a diffuse bsdf with reflectance 0.5 (as Mitsuba does)");
  }
  props.checkAllUsed();
  scene_.meshes.push_back(std::move(mesh));
}

}  // namespace mlt::mitsuba
