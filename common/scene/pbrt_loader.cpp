// pbrt-v3 front end: directives -> SceneDesc. Conventions in pbrt_loader.h; the subset in scenes/README.md.
#include "common/scene/pbrt_loader.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "common/scene/camera_transform.h"
#include "common/scene/material_tables.h"
#include "common/scene/mesh_readers.h"
#include "common/scene/mesh_utils.h"
#include "common/scene/pbrt_internal.h"
#include "common/scene/scene_files.h"

namespace fs = std::filesystem;

namespace mlt {

float pbrtRoughnessToAlpha(float roughness) {
  const double x = std::log(std::max(double(roughness), 1e-3));
  return float(1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x);
}

namespace pbrt {

// ---------------------------------------------------------------------------------------------------
// Token stream
// ---------------------------------------------------------------------------------------------------
const Token& Loader::next(const char* what) {
  if (pos_ >= tokens_.size()) {
    const Token& last = tokens_.empty() ? Token() : tokens_.back();
    throw SceneError(last.file.empty() ? scene_.sourceFile : last.file, last.line,
                     std::string("unexpected end of file: expected ") + what);
  }
  return tokens_[pos_++];
}

std::string Loader::readString(const char* what) {
  const Token& t = next(what);
  if (t.kind != Token::Kind::String) failAt(t, std::string("expected ") + what + " (a quoted string), got '" + t.text + "'");
  return t.text;
}

double Loader::readNumber(const char* what) {
  const Token& t = next(what);
  if (t.kind != Token::Kind::Number) failAt(t, std::string("expected ") + what + " (a number), got '" + t.text + "'");
  return t.number;
}

std::vector<double> Loader::readNumbers(size_t n, const char* what) {
  std::vector<double> v;
  const bool bracket = peek() && peek()->kind == Token::Kind::Open;
  if (bracket) next(what);
  for (size_t i = 0; i < n; ++i) v.push_back(readNumber(what));
  if (bracket) {
    const Token& t = next("]");
    if (t.kind != Token::Kind::Close) failAt(t, std::string("expected ']' after ") + what);
  }
  return v;
}

ParamList Loader::readParams(const std::string& directive, const Token& where) {
  ParamList list(directive, where);
  while (peek() && peek()->kind == Token::Kind::String) {
    const Token decl = next("parameter");
    Param p;
    p.where = decl;
    const auto space = decl.text.find_first_of(" \t");
    if (space == std::string::npos) failAt(decl, directive + ": expected a \"type name\" parameter, got \"" + decl.text + "\"");
    p.type = decl.text.substr(0, space);
    const auto nameStart = decl.text.find_first_not_of(" \t", space);
    if (nameStart == std::string::npos) failAt(decl, directive + ": parameter \"" + decl.text + "\" has no name");
    p.name = decl.text.substr(nameStart);
    if (p.name.find_first_of(" \t") != std::string::npos) failAt(decl, directive + ": malformed parameter \"" + decl.text + "\"");
    auto value = [&](const Token& v) {
      if (v.kind == Token::Kind::Number) p.numbers.push_back(v.number);
      else if (v.kind == Token::Kind::String) p.strings.push_back(v.text);
      else if (v.kind == Token::Kind::Word && (v.text == "true" || v.text == "false")) p.strings.push_back(v.text);
      else failAt(v, directive + ": bad value '" + v.text + "' for parameter '" + p.name + "'");
    };
    const Token& v = next("a parameter value");
    if (v.kind == Token::Kind::Open) {
      for (;;) {
        const Token& e = next("']'");
        if (e.kind == Token::Kind::Close) break;
        value(e);
      }
    } else {
      value(v);
    }
    if (!p.numbers.empty() && !p.strings.empty()) failAt(decl, directive + ": parameter '" + p.name + "' mixes numbers and strings");
    const bool wantsStrings = p.type == "string" || p.type == "texture" || p.type == "bool";
    if (wantsStrings && !p.numbers.empty()) failAt(decl, directive + ": parameter '" + p.name + "' needs strings");
    if (!wantsStrings && p.type != "spectrum" && !p.strings.empty())
      failAt(decl, directive + ": parameter '" + p.name + "' needs numbers");
    list.add(std::move(p));
  }
  return list;
}

std::string Loader::resolve(const Token& where, const std::string& file, const char* what) {
  const ResolvedFile r = resolveSceneFile(file, where.file, mainDir_, root_);
  if (!r.error.empty()) failAt(where, std::string(what) + ": " + r.error);
  if (std::find(scene_.referencedFiles.begin(), scene_.referencedFiles.end(), r.path) == scene_.referencedFiles.end())
    scene_.referencedFiles.push_back(r.path);
  return r.path;
}

void Loader::include(const Token& where) {
  const std::string file = resolve(where, readString("an Include file name"), "included file");
  const std::string key = fs::weakly_canonical(file).string();
  if (includeStack_.count(key)) failAt(where, "recursive Include of '" + file + "'");
  if (includeStack_.size() > 32) failAt(where, "Includes nested too deeply");
  std::vector<Token> inc = tokenizeFile(file);
  // Splice the included tokens in place; a sentinel word marks where the include ends.
  Token end;
  end.kind = Token::Kind::Word;
  end.text = "\x01EndInclude";
  end.file = file;
  end.line = inc.empty() ? 0 : inc.back().line;
  end.number = 0;
  inc.push_back(end);
  tokens_.insert(tokens_.begin() + long(pos_), inc.begin(), inc.end());
  includeStack_.insert(key);
  // Remember the key on the sentinel (its text after the marker).
  tokens_[pos_ + inc.size() - 1].text += key;
}

// ---------------------------------------------------------------------------------------------------
// Scene structure
// ---------------------------------------------------------------------------------------------------
SceneDesc Loader::load(const std::string& path) {
  scene_.sourceFile = path;
  scene_.camera.width = 640;  // pbrt's Film defaults
  scene_.camera.height = 480;
  scene_.camera.fovDeg = 90;
  scene_.camera.fovAxis = CameraDesc::FovAxis::Smaller;
  mainDir_ = fs::path(path).parent_path().string();
  includeStack_.insert(fs::weakly_canonical(path).string());
  tokens_ = tokenizeFile(path);
  while (pos_ < tokens_.size()) {
    const Token t = next("a directive");  // a copy: Include inserts into tokens_
    if (t.kind != Token::Kind::Word) failAt(t, "expected a directive, got '" + t.text + "'");
    directive(t);
  }
  if (!haveCamera_) throw SceneError(path, 0, "the scene has no Camera directive");
  if (!haveIntegrator_) scene_.maxDepth = 5 + 1;  // pbrt's default path integrator, maxdepth 5
  return std::move(scene_);
}

void Loader::directive(const Token& t) {
  const std::string& d = t.text;
  auto vec3 = [&](const char* what) {
    const auto v = readNumbers(3, what);
    return Vec3(float(v[0]), float(v[1]), float(v[2]));
  };
  if (d.rfind("\x01EndInclude", 0) == 0) {
    includeStack_.erase(d.substr(std::string("\x01EndInclude").size()));
  } else if (d == "Include") {
    include(t);
  } else if (d == "Translate") {
    gs_.ctm = gs_.ctm * Transform::translate(vec3("Translate x y z"));
  } else if (d == "Scale") {
    gs_.ctm = gs_.ctm * Transform::scale(vec3("Scale x y z"));
  } else if (d == "Rotate") {
    const auto v = readNumbers(4, "Rotate angle x y z");
    const Vec3 axis{float(v[1]), float(v[2]), float(v[3])};
    if (!(length(axis) > 0)) failAt(t, "Rotate: zero axis");
    gs_.ctm = gs_.ctm * Transform::rotate(axis, v[0]);
  } else if (d == "LookAt") {
    const auto v = readNumbers(9, "LookAt eye look up");
    const Vec3 eye{float(v[0]), float(v[1]), float(v[2])}, look{float(v[3]), float(v[4]), float(v[5])},
        up{float(v[6]), float(v[7]), float(v[8])};
    if (const std::string problem = lookAtProblem(eye, look, up); !problem.empty()) failAt(t, "LookAt: " + problem);
    try {
      // pbrt's LookAt is the world-to-camera inverse of Mitsuba's lookat (same columns: up x dir, up, dir).
      const Transform camToWorld = Transform::lookAt(eye, look, up);
      gs_.ctm = gs_.ctm * camToWorld.inverse();
    } catch (const SceneError&) {
      throw;
    } catch (const std::exception& e) {
      failAt(t, std::string("LookAt: ") + e.what());
    }
  } else if (d == "Transform" || d == "ConcatTransform") {
    const auto v = readNumbers(16, (d + " (16 numbers)").c_str());
    Transform m;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m.m[r][c] = v[size_t(c) * 4 + r];  // pbrt's matrices are transposed
    if (!m.isFinite()) failAt(t, d + ": not finite");
    gs_.ctm = d == "Transform" ? m : gs_.ctm * m;
  } else if (d == "Identity") {
    gs_.ctm = Transform();
  } else if (d == "ReverseOrientation") {
    gs_.reverseOrientation = !gs_.reverseOrientation;
  } else if (d == "CoordinateSystem") {
    namedCoordSys_[readString("a coordinate system name")] = gs_.ctm;
  } else if (d == "CoordSysTransform") {
    const std::string name = readString("a coordinate system name");
    auto it = namedCoordSys_.find(name);
    if (it == namedCoordSys_.end()) failAt(t, "CoordSysTransform: unknown coordinate system '" + name + "'");
    gs_.ctm = it->second;
  } else if (d == "AttributeBegin") {
    stack_.push_back(gs_);
  } else if (d == "AttributeEnd") {
    if (stack_.empty()) failAt(t, "AttributeEnd without AttributeBegin");
    gs_ = stack_.back();
    stack_.pop_back();
  } else if (d == "TransformBegin") {
    transformStack_.push_back(gs_.ctm);
  } else if (d == "TransformEnd") {
    if (transformStack_.empty()) failAt(t, "TransformEnd without TransformBegin");
    gs_.ctm = transformStack_.back();
    transformStack_.pop_back();
  } else if (d == "Camera") {
    camera(t);
  } else if (d == "Film") {
    const std::string type = readString("a film type");
    ParamList p = readParams("Film \"" + type + "\"", t);
    if (type != "image") failAt(t, "Film: unsupported type '" + type + "' (supported: image)");
    const long long w = p.optInt("xresolution").value_or(640), h = p.optInt("yresolution").value_or(480);
    if (w <= 0 || h <= 0 || w > 65536 || h > 65536) p.fail("resolution must be in [1, 65536]");
    scene_.camera.width = int(w);
    scene_.camera.height = int(h);
    if (const Param* c = p.find("cropwindow")) p.fail(*c, "Film: cropwindow is not supported");
    p.optString("filename");  // the output name is the job's choice
    p.ignore({"diagonal"});
    p.checkAllUsed();
  } else if (d == "Sampler") {
    const std::string type = readString("a sampler type");
    ParamList p = readParams("Sampler \"" + type + "\"", t);
    if (auto n = p.optInt("pixelsamples")) {
      if (*n <= 0) p.fail("pixelsamples must be positive");
      scene_.sampleCount = int(*n);
    }
    // Sample patterns do not change the expected image.
    p.ignore({"jitter", "xsamples", "ysamples", "dimensions"});
    p.checkAllUsed();
  } else if (d == "PixelFilter") {
    const std::string type = readString("a filter type");
    ParamList p = readParams("PixelFilter \"" + type + "\"", t);
    if (type != "box")
      scene_.warnings.push_back(at(t) + ": PixelFilter '" + type + "' is replaced by a box filter (one pixel)");
    p.ignore({"xwidth", "ywidth", "alpha", "B", "C", "tau"});
    p.checkAllUsed();
  } else if (d == "Integrator") {
    const std::string type = readString("an integrator type");
    ParamList p = readParams("Integrator \"" + type + "\"", t);
    static const std::set<std::string> known = {"path", "bdpt", "mlt", "volpath", "directlighting", "sppm", "whitted"};
    if (!known.count(type)) failAt(t, "Integrator: unknown type '" + type + "'");
    const long long depth = p.optInt("maxdepth").value_or(5);
    if (depth < 0) p.fail("maxdepth must be >= 0");
    scene_.maxDepth = int(depth) + 1;  // bounces -> segments (pbrt_loader.h)
    haveIntegrator_ = true;
    p.ignore({"rrthreshold", "lightsamplestrategy", "pixelbounds", "visualizestrategies", "visualizeweights",
              "bootstrapsamples", "chains", "mutationsperpixel", "largestepprobability", "sigma"});
    p.checkAllUsed();
  } else if (d == "Accelerator") {
    readString("an accelerator type");
    ParamList p = readParams("Accelerator", t);
    for (const char* n : {"maxprims", "splitmethod", "intersectcost", "traversalcost", "emptybonus", "maxdepth"})
      p.ignore({n});
    p.checkAllUsed();
  } else if (d == "WorldBegin") {
    if (inWorld_) failAt(t, "WorldBegin inside the world block");
    inWorld_ = true;
    gs_.ctm = Transform();
    namedCoordSys_["world"] = gs_.ctm;
  } else if (d == "WorldEnd") {
    if (!inWorld_) failAt(t, "WorldEnd without WorldBegin");
    inWorld_ = false;
  } else if (d == "Shape") {
    shape(t);
  } else if (d == "Material") {
    const std::string type = readString("a material type");
    ParamList p = readParams("Material \"" + type + "\"", t);
    gs_.material = makeMaterial(p, type, t);
  } else if (d == "MakeNamedMaterial") {
    const std::string name = readString("a material name");
    ParamList p = readParams("MakeNamedMaterial \"" + name + "\"", t);
    const auto type = p.optString("type");
    if (!type) p.fail("MakeNamedMaterial needs a \"string type\"");
    namedMaterials_[name] = makeMaterial(p, *type, t);
  } else if (d == "NamedMaterial") {
    const std::string name = readString("a material name");
    auto it = namedMaterials_.find(name);
    if (it == namedMaterials_.end()) failAt(t, "NamedMaterial: no material named '" + name + "' (define it first)");
    gs_.material = it->second;
  } else if (d == "Texture") {
    texture(t);
  } else if (d == "LightSource") {
    lightSource(t);
  } else if (d == "AreaLightSource") {
    const std::string type = readString("an area light type");
    ParamList p = readParams("AreaLightSource \"" + type + "\"", t);
    if (type != "diffuse") failAt(t, "AreaLightSource: unsupported type '" + type + "' (supported: diffuse)");
    AreaLightState a;
    a.L = p.optColor("L").value_or(Color(1.0f)) * p.optColor("scale").value_or(Color(1.0f));
    if (!a.L.isFinite() || a.L.r < 0 || a.L.g < 0 || a.L.b < 0) p.fail("L must be finite and non-negative");
    a.twoSided = p.getBool("twosided", false);
    p.ignore({"nsamples", "samples"});
    p.checkAllUsed();
    gs_.areaLight = a;
  } else if (d == "ObjectBegin") {
    const std::string name = readString("an object name");
    if (currentObject_) failAt(t, "ObjectBegin inside ObjectBegin");
    if (objects_.count(name)) failAt(t, "ObjectBegin: object '" + name + "' is defined twice");
    stack_.push_back(gs_);
    currentObject_ = &objects_[name];
  } else if (d == "ObjectEnd") {
    if (!currentObject_) failAt(t, "ObjectEnd without ObjectBegin");
    currentObject_ = nullptr;
    if (stack_.empty()) failAt(t, "ObjectEnd: attribute stack is empty");
    gs_ = stack_.back();
    stack_.pop_back();
  } else if (d == "ObjectInstance") {
    const std::string name = readString("an object name");
    if (currentObject_) failAt(t, "ObjectInstance inside ObjectBegin");
    auto it = objects_.find(name);
    if (it == objects_.end()) failAt(t, "ObjectInstance: no object named '" + name + "'");
    // Object shapes are stored in the space current at ObjectBegin; the instance's CTM goes on top.
    for (const MeshDesc& m : it->second) {
      MeshDesc copy = m;
      copy.name = m.name + " (instance at " + at(t) + ")";
      try {
        transformMesh(copy, gs_.ctm, /*keepOrientation=*/true);
        validateMesh(copy);
      } catch (const std::exception& e) {
        failAt(t, "ObjectInstance '" + name + "': " + e.what());
      }
      scene_.meshes.push_back(std::move(copy));
    }
  } else if (d == "MakeNamedMedium" || d == "MediumInterface") {
    failAt(t, d + ": participating media are not supported");
  } else if (d == "ActiveTransform" || d == "TransformTimes") {
    failAt(t, d + ": motion blur (animated transforms) is not supported");
  } else {
    failAt(t, "unknown or unsupported directive '" + d + "'");
  }
}

void Loader::camera(const Token& where) {
  const std::string type = readString("a camera type");
  ParamList p = readParams("Camera \"" + type + "\"", where);
  if (type != "perspective") failAt(where, "Camera: unsupported type '" + type + "' (supported: perspective)");
  if (haveCamera_) failAt(where, "a second Camera");
  if (inWorld_) failAt(where, "Camera inside the world block");
  haveCamera_ = true;
  CameraDesc& cam = scene_.camera;
  // The rule of a Mitsuba sensor's to_world, on the transform current here (world to camera: its inverse
  // passes or fails alike).
  if (const std::string problem = cameraTransformProblem(gs_.ctm); !problem.empty())
    failAt(where, "Camera: the current transform " + problem);
  try {
    namedCoordSys_["camera"] = gs_.ctm.inverse();
    cam.toWorld = gs_.ctm.inverse() * Transform::scale(Vec3(-1, 1, 1));  // pbrt +x right -> our +x left
  } catch (const std::exception& e) {
    failAt(where, std::string("Camera: the camera transform is singular: ") + e.what());
  }
  cam.fovDeg = float(p.getFloat("fov", 90));
  if (!(cam.fovDeg > 0 && cam.fovDeg < 180)) p.fail("fov must be in (0, 180)");
  cam.fovAxis = CameraDesc::FovAxis::Smaller;
  cam.nearClip = float(p.getFloat("hither", 1e-3));
  if (!(cam.nearClip > 0)) p.fail("hither must be positive");
  const double lens = p.getFloat("lensradius", 0), focus = p.getFloat("focaldistance", 1e6);
  if (lens < 0 || !(focus > 0)) p.fail("need lensradius >= 0 and focaldistance > 0");
  if (lens > 0) {
    cam.type = CameraDesc::Type::ThinLens;
    cam.apertureRadius = float(lens);
    cam.focusDistance = float(focus);
  }
  for (const char* n : {"frameaspectratio", "screenwindow"})
    if (const Param* q = p.find(n)) p.fail(*q, std::string("Camera: '") + n + "' is not supported");
  p.ignore({"yon", "shutteropen", "shutterclose", "halffov"});
  p.checkAllUsed();
}

// ---------------------------------------------------------------------------------------------------
// Shapes
// ---------------------------------------------------------------------------------------------------
void Loader::shape(const Token& where) {
  const std::string type = readString("a shape type");
  ParamList p = readParams("Shape \"" + type + "\"", where);
  MeshDesc mesh;
  bool analytic = false;
  if (type == "trianglemesh") {
    const auto idx = p.numbers("indices", {"integer"});
    const auto P = p.numbers("P", {"point"});
    if (P.empty() || P.size() % 3) p.fail("trianglemesh needs \"point P\" with 3 numbers per vertex");
    const size_t nv = P.size() / 3;
    if (idx.empty() && nv == 3) mesh.indices = {0, 1, 2};
    if (!idx.empty() && idx.size() % 3) p.fail("trianglemesh: the number of indices is not a multiple of 3");
    for (double i : idx) {
      if (i < 0 || i >= double(nv)) p.fail("trianglemesh: index " + std::to_string(long(i)) + " is out of range");
      mesh.indices.push_back(uint32_t(i));
    }
    for (size_t i = 0; i < nv; ++i) mesh.positions.emplace_back(float(P[3 * i]), float(P[3 * i + 1]), float(P[3 * i + 2]));
    const auto N = p.numbers("N", {"normal"});
    if (!N.empty()) {
      if (N.size() != P.size()) p.fail("trianglemesh: N needs one normal per vertex");
      for (size_t i = 0; i < nv; ++i) mesh.normals.emplace_back(float(N[3 * i]), float(N[3 * i + 1]), float(N[3 * i + 2]));
    }
    for (const char* uvName : {"uv", "st"}) {
      const auto uv = p.numbers(uvName, {"float", "point2"});
      if (uv.empty()) continue;
      if (!mesh.uvs.empty()) p.fail("trianglemesh: give uv or st, not both");
      if (uv.size() != 2 * nv) p.fail(std::string("trianglemesh: ") + uvName + " needs two values per vertex");
      for (size_t i = 0; i < nv; ++i) mesh.uvs.emplace_back(float(uv[2 * i]), float(uv[2 * i + 1]));
    }
    if (const Param* s = p.find("S")) p.fail(*s, "trianglemesh: per-vertex tangents S are not supported");
  } else if (type == "plymesh") {
    const auto file = p.optString("filename");
    if (!file) p.fail("plymesh needs a \"string filename\"");
    const std::string path = resolve(p.find("filename")->where, *file, "PLY file");
    try {
      mesh = readPly(path);  // positions, the file's normals (pbrt uses them) and uvs, in object space
    } catch (const SceneError& e) {
      failAt(where, std::string("Shape \"plymesh\": cannot load mesh: ") + e.what());
    }
    mesh.name = fs::path(*file).filename().string() + " (" + at(where) + ")";
  } else if (type == "sphere") {
    analytic = true;
    const double r = p.getFloat("radius", 1);
    if (!(r > 0)) p.fail("sphere radius must be positive");
    for (const char* n : {"zmin", "zmax", "phimax"})
      if (const Param* q = p.find(n)) p.fail(*q, std::string("Shape \"sphere\": partial spheres ('") + n + "') are not supported");
    mesh = makeSphere();
    mesh.convex = true;
    transformMesh(mesh, Transform::scale(Vec3(float(r))), true);
  } else if (type == "disk") {
    analytic = true;
    const double r = p.getFloat("radius", 1), h = p.getFloat("height", 0);
    if (!(r > 0)) p.fail("disk radius must be positive");
    if (p.getFloat("innerradius", 0) != 0) p.fail(*p.find("innerradius"), "Shape \"disk\": innerradius is not supported");
    if (const Param* q = p.find("phimax")) p.fail(*q, "Shape \"disk\": partial disks (phimax) are not supported");
    mesh = makeDisk();
    transformMesh(mesh, Transform::translate(Vec3(0, 0, float(h))) * Transform::scale(Vec3(float(r))), true);
  } else {
    failAt(where, "Shape: unsupported type '" + type + "' (supported: trianglemesh, plymesh, sphere, disk)");
  }
  for (const char* n : {"alpha", "shadowalpha"})
    if (const Param* q = p.find(n)) p.fail(*q, std::string("Shape: '") + n + "' (cut-outs) is not supported");
  p.checkAllUsed();
  if (mesh.name.empty()) mesh.name = type + " at " + at(where);
  addMesh(std::move(mesh), analytic, where);
}

void Loader::addMesh(MeshDesc mesh, bool analytic, const Token& where) {
  if (mesh.indices.empty()) failAt(where, "Shape: the mesh has no triangles");
  try {
    validateMesh(mesh);
    transformMesh(mesh, gs_.ctm, /*keepOrientation=*/true);
    validateMesh(mesh);
  } catch (const std::exception& e) {
    failAt(where, std::string("Shape: ") + e.what());
  }
  if (!mesh.normals.empty() && !analytic) {
    // pbrt: n = FaceForward(n, ns): each triangle faces its shading normals.
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
      uint32_t* i = &mesh.indices[t];
      const Vec3 ng = cross(mesh.positions[i[1]] - mesh.positions[i[0]], mesh.positions[i[2]] - mesh.positions[i[0]]);
      const Vec3 ns = mesh.normals[i[0]] + mesh.normals[i[1]] + mesh.normals[i[2]];
      if (dot(ng, ns) < 0) std::swap(i[1], i[2]);
    }
  } else if (gs_.reverseOrientation) {
    flipMesh(mesh);
  }
  mesh.bsdf = gs_.material >= 0 ? gs_.material : defaultMaterial();
  if (currentObject_) {
    if (gs_.areaLight) failAt(where, "Shape: area lights inside ObjectBegin are not supported (nor in pbrt)");
    // Stored in world space at definition; ObjectInstance applies its CTM on top. Undo nothing here: pbrt
    // instances use the object's shapes in the space current at ObjectBegin, which for the usual
    // "ObjectBegin at identity" is world space.
    currentObject_->push_back(std::move(mesh));
    return;
  }
  if (gs_.areaLight) {
    if (!hasPositiveArea(mesh)) failAt(where, "Shape: an area light's shape must have a positive, finite area");
    mesh.emission = gs_.areaLight->L;
    if (gs_.areaLight->twoSided) {
      MeshDesc back = mesh;
      flipMesh(back);
      back.name += " (back side)";
      scene_.meshes.push_back(std::move(back));
    }
  }
  scene_.meshes.push_back(std::move(mesh));
}

}  // namespace pbrt

SceneDesc loadPbrtScene(const std::string& path, const std::string& root) { return pbrt::Loader(root).load(path); }

}  // namespace mlt
