// Mitsuba XML front end: document structure (<default>, $name, <include>, ids), sensor, film,
// integrator and non-area emitters. Shapes are in mitsuba_shapes.cpp, BSDFs/textures in mitsuba_bsdf.cpp.
#include "common/scene/mitsuba_loader.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "common/scene/camera_transform.h"
#include "common/scene/mitsuba_internal.h"
#include "common/scene/scene_files.h"

namespace fs = std::filesystem;

namespace mlt {
namespace mitsuba {

namespace {
bool isIdentChar(char c) { return std::isalnum((unsigned char)c) || c == '_'; }

std::string lowerCopy(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}
}  // namespace

// ---------------------------------------------------------------------------------------------------------
// Document structure
// ---------------------------------------------------------------------------------------------------------

SceneDesc Loader::load(const std::string& path) {
  mainFile_ = path;
  mainDir_ = fs::path(path).parent_path().string();
  scene_.sourceFile = path;
  params_ = defines_;
  docs_.push_back(std::make_unique<XmlElement>(parseXmlFile(path)));
  XmlElement& root = *docs_.back();
  if (root.name != "scene") failAt(root, "the root element must be <scene>");
  checkAttributes(root, {"version"});
  if (const XmlAttribute* v = root.find("version")) {
    try {
      majorVersion_ = std::stoi(v->value);
    } catch (const std::exception&) {
      failAt(root, "bad version '" + v->value + "'");
    }
  } else {
    warn(root, "<scene> has no version attribute; assuming Mitsuba 3 conventions");
  }
  includeStack_.insert(fs::weakly_canonical(path).string());
  processSceneChildren(root, 0);
  if (!haveSensor_) {
    warn(root, "the scene has no <sensor>; using a perspective camera at the origin looking down +z");
    scene_.camera.width = 768;
    scene_.camera.height = 576;
  }
  return std::move(scene_);
}

void Loader::processSceneChildren(XmlElement& root, int depth) {
  for (XmlElement& c : root.children) {
    if (c.name == "default") {
      checkAttributes(c, {"name", "value"});
      const std::string& name = requireAttr(c, "name");
      const std::string& value = requireAttr(c, "value");
      if (name.empty() || !std::all_of(name.begin(), name.end(), isIdentChar))
        failAt(c, "parameter name '" + name + "' must be letters, digits and '_'");
      if (!defines_.count(name)) params_[name] = value;  // the command line wins
      continue;
    }
    substitute(c);
    if (c.name == "include") {
      checkAttributes(c, {"filename"});
      const std::string file = resolveFile(c, requireAttr(c, "filename"), "included file");
      const std::string key = fs::weakly_canonical(file).string();
      if (includeStack_.count(key)) failAt(c, "recursive include of '" + file + "'");
      if (depth > 32) failAt(c, "includes nested too deeply");
      docs_.push_back(std::make_unique<XmlElement>(parseXmlFile(file)));
      XmlElement& inc = *docs_.back();
      if (inc.name != "scene") failAt(inc, "the root element of an included file must be <scene>");
      includeStack_.insert(key);
      processSceneChildren(inc, depth + 1);
      includeStack_.erase(key);
    } else if (c.name == "bsdf") {
      const int idx = parseBsdf(c);
      if (const XmlAttribute* id = c.find("id")) {
        registerId(c, "bsdf");
        namedBsdfs_[id->value] = idx;
      }
    } else if (c.name == "texture") {
      const XmlAttribute* id = c.find("id");
      if (!id) failAt(c, "a top-level <texture> needs an id");
      TextureDesc t = parseTexture(c);
      registerId(c, "texture");
      namedTextures_[id->value] = t;
    } else if (c.name == "shape") {
      parseShape(c);
    } else if (c.name == "emitter") {
      parseEmitter(c);
    } else if (c.name == "sensor") {
      if (haveSensor_) {
        warn(c, "more than one <sensor>; only the first is used");
        continue;
      }
      parseSensor(c);
      haveSensor_ = true;
    } else if (c.name == "integrator") {
      parseIntegrator(c);
    } else if (c.name == "medium" || c.name == "phase") {
      failAt(c, "participating media are not supported");
    } else {
      failAt(c, "unsupported element in <scene> (expected shape, bsdf, texture, emitter, sensor, integrator, "
                "default or include)");
    }
  }
}

void Loader::registerId(const XmlElement& el, const std::string& kind) {
  const std::string& id = requireAttr(el, "id");
  if (idKinds_.count(id)) failAt(el, "id '" + id + "' is already used by a " + idKinds_[id]);
  idKinds_[id] = kind;
}

std::string Loader::substituteValue(const XmlElement& el, const XmlAttribute& a) const {
  const std::string& v = a.value;
  std::string out;
  for (size_t i = 0; i < v.size(); ++i) {
    if (v[i] != '$') {
      out += v[i];
      continue;
    }
    size_t j = i + 1;
    while (j < v.size() && isIdentChar(v[j])) ++j;
    const std::string name = v.substr(i + 1, j - i - 1);
    if (name.empty()) throw SceneError(el.file, a.line, describe(el) + ": '$' without a parameter name in '" + v + "'");
    auto it = params_.find(name);
    if (it == params_.end())
      throw SceneError(el.file, a.line, describe(el) + ": undefined parameter $" + name +
                                            " (declare it with <default name=\"" + name + "\" value=...> or define it)");
    out += it->second;
    i = j - 1;
  }
  return out;
}

void Loader::substitute(XmlElement& el) {
  for (XmlAttribute& a : el.attributes)
    if (a.value.find('$') != std::string::npos) a.value = substituteValue(el, a);
  for (XmlElement& c : el.children) {
    if (c.name == "default" || c.name == "include") failAt(c, "<" + c.name + "> is only allowed directly in <scene>");
    substitute(c);
  }
}

void Loader::collect(const XmlElement& el, PropertyList& props, std::vector<const XmlElement*>& nested) const {
  static const char* kNested[] = {"bsdf", "texture", "emitter", "film", "sampler", "rfilter", "integrator",
                                  "ref",  "shape",   "medium",  "phase", "sensor", "subsurface"};
  for (const XmlElement& c : el.children) {
    if (props.addFromElement(c)) continue;
    bool ok = false;
    for (const char* n : kNested) ok = ok || c.name == n;
    if (!ok) failAt(c, "unknown element inside " + describe(el));
    nested.push_back(&c);
  }
}

std::string Loader::resolveFile(const XmlElement& el, const std::string& filename, const char* what) {
  const ResolvedFile r = resolveSceneFile(filename, el.file, mainDir_, root_);
  if (!r.error.empty()) failAt(el, std::string("filename (") + what + "): " + r.error);
  if (std::find(scene_.referencedFiles.begin(), scene_.referencedFiles.end(), r.path) == scene_.referencedFiles.end())
    scene_.referencedFiles.push_back(r.path);
  return r.path;
}

void Loader::warn(const XmlElement& el, const std::string& msg) {
  scene_.warnings.push_back(el.file + ":" + std::to_string(el.line) + ": " + msg);
}

int Loader::defaultBsdf() {
  if (defaultBsdf_ < 0) {
    BsdfDesc d;
    d.type = BsdfDesc::Type::Diffuse;
    d.id = "<default diffuse 0.5>";
    d.reflectance.value = Color(0.5f);
    defaultBsdf_ = int(scene_.bsdfs.size());
    scene_.bsdfs.push_back(d);
  }
  return defaultBsdf_;
}

// ---------------------------------------------------------------------------------------------------------
// Sensor, film, sampler, rfilter
// ---------------------------------------------------------------------------------------------------------

void Loader::parseSensor(const XmlElement& el) {
  checkAttributes(el, {"type", "id", "name"});
  const std::string type = requireAttr(el, "type");
  CameraDesc& cam = scene_.camera;
  if (type == "perspective") cam.type = CameraDesc::Type::Perspective;
  else if (type == "thinlens") cam.type = CameraDesc::Type::ThinLens;
  else failAt(el, "unknown or unsupported sensor type '" + type + "' (supported: perspective, thinlens)");
  PropertyList props(el);
  std::vector<const XmlElement*> nested;
  collect(el, props, nested);

  if (props.has("fov") && props.has("focal_length")) failAt(el, "give either 'fov' or 'focal_length', not both");
  if (auto fov = props.optFloat("fov")) {
    if (!(*fov > 0 && *fov < 180)) props.fail(*props.find("fov"), "fov must be in (0, 180) degrees");
    cam.fovDeg = float(*fov);
    const std::string axis = lowerCopy(props.optString("fov_axis").value_or("x"));
    if (axis == "x") cam.fovAxis = CameraDesc::FovAxis::X;
    else if (axis == "y") cam.fovAxis = CameraDesc::FovAxis::Y;
    else if (axis == "diagonal") cam.fovAxis = CameraDesc::FovAxis::Diagonal;
    else if (axis == "smaller") cam.fovAxis = CameraDesc::FovAxis::Smaller;
    else if (axis == "larger") cam.fovAxis = CameraDesc::FovAxis::Larger;
    else props.fail(*props.find("fov_axis"), "fov_axis must be x, y, diagonal, smaller or larger");
  } else {
    // Mitsuba: a 35 mm-equivalent focal length (default 50mm) gives the diagonal field of view.
    double f = 50;
    if (const Prop* p = props.find("focal_length")) {
      if (p->kind == Prop::Kind::String) {
        std::string s = p->s;
        if (s.size() > 2 && s.substr(s.size() - 2) == "mm") s = s.substr(0, s.size() - 2);
        f = parseNumber(*p->el, "value", s);
      } else {
        f = props.getFloat("focal_length", 50);
      }
      if (!(f > 0)) props.fail(*p, "focal_length must be positive");
    }
    if (props.has("fov_axis")) props.fail(*props.find("fov_axis"), "fov_axis needs fov");
    cam.fovDeg = float(2.0 * std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * f)) * 180.0 / M_PI);
    cam.fovAxis = CameraDesc::FovAxis::Diagonal;
  }
  cam.nearClip = float(props.getFloat("near_clip", 1e-2));
  const double farClip = props.getFloat("far_clip", 1e4);
  if (!(cam.nearClip > 0) || !(farClip > cam.nearClip)) failAt(el, "need 0 < near_clip < far_clip");
  if (auto t = props.optTransform("to_world")) {
    if (const std::string problem = cameraTransformProblem(*t); !problem.empty())
      props.fail(*props.find("to_world"), "a sensor's to_world " + problem);
    cam.toWorld = *t;
  }
  if (cam.type == CameraDesc::Type::ThinLens) {
    auto ap = props.optFloat("aperture_radius");
    auto fd = props.optFloat("focus_distance");
    if (!ap) failAt(el, "thinlens needs aperture_radius");
    if (!fd) failAt(el, "thinlens needs focus_distance");
    if (!(*ap >= 0) || !(*fd > 0)) failAt(el, "need aperture_radius >= 0 and focus_distance > 0");
    cam.apertureRadius = float(*ap);
    cam.focusDistance = float(*fd);
  } else {
    props.ignore({"focus_distance"});  // a pinhole has no focal plane (exporters write it anyway)
  }
  for (const char* n : {"principal_point_offset_x", "principal_point_offset_y"})
    if (props.getFloat(n, 0) != 0) failAt(el, std::string(n) + " is not supported");
  props.ignore({"shutter_open", "shutter_close", "shutter_open_time"});
  props.checkAllUsed();

  cam.width = 768;  // Mitsuba's hdrfilm default
  cam.height = 576;
  for (const XmlElement* n : nested) {
    if (n->name == "film") {
      checkAttributes(*n, {"type", "id", "name"});
      const std::string ft = requireAttr(*n, "type");
      if (ft == "ldrfilm") warn(*n, "ldrfilm is rendered like hdrfilm (linear radiance, no tonemapping)");
      else if (ft != "hdrfilm") failAt(*n, "unsupported film type '" + ft + "' (supported: hdrfilm)");
      PropertyList fp(*n);
      std::vector<const XmlElement*> fn;
      collect(*n, fp, fn);
      const long long w = fp.getInt("width", 768), h = fp.getInt("height", 576);
      if (w <= 0 || h <= 0 || w > 65536 || h > 65536) failAt(*n, "film width/height out of range");
      cam.width = int(w);
      cam.height = int(h);
      if (fp.getInt("crop_offset_x", 0) != 0 || fp.getInt("crop_offset_y", 0) != 0 ||
          fp.getInt("crop_width", w) != w || fp.getInt("crop_height", h) != h)
        failAt(*n, "crop windows are not supported");
      fp.ignore({"file_format", "pixel_format", "component_format", "banner", "high_quality_edges", "attach_log",
                 "gamma", "exposure", "tonemap_method", "key", "burn", "sample_border", "compensate"});
      fp.checkAllUsed();
      for (const XmlElement* f : fn) {
        if (f->name != "rfilter") failAt(*f, "unexpected element inside <film>");
        checkAttributes(*f, {"type", "id", "name"});
        const std::string rt = requireAttr(*f, "type");
        static const char* kFilters[] = {"box", "tent", "gaussian", "mitchell", "catmullrom", "lanczos"};
        if (std::none_of(std::begin(kFilters), std::end(kFilters), [&](const char* k) { return rt == k; }))
          failAt(*f, "unknown rfilter type '" + rt + "'");
        if (rt != "box") warn(*f, "rfilter '" + rt + "' is replaced by a box filter (one pixel)");
        PropertyList rp(*f);
        std::vector<const XmlElement*> rn;
        collect(*f, rp, rn);
        if (!rn.empty()) failAt(*rn.front(), "unexpected element inside <rfilter>");
        rp.ignore({"radius", "stddev", "b", "c", "lobes"});
        rp.checkAllUsed();
      }
    } else if (n->name == "sampler") {
      checkAttributes(*n, {"type", "id", "name"});
      const std::string st = requireAttr(*n, "type");
      static const char* kSamplers[] = {"independent", "stratified", "multijitter", "ldsampler", "halton",
                                        "hammersley",  "sobol",      "orthogonal",  "ldsampler"};
      if (std::none_of(std::begin(kSamplers), std::end(kSamplers), [&](const char* k) { return st == k; }))
        failAt(*n, "unknown sampler type '" + st + "'");
      PropertyList sp(*n);
      std::vector<const XmlElement*> sn;
      collect(*n, sp, sn);
      if (!sn.empty()) failAt(*sn.front(), "unexpected element inside <sampler>");
      if (auto spp = sp.optInt("sample_count")) {
        if (*spp <= 0 || *spp > (1 << 30)) failAt(*n, "sample_count must be in [1, 2^30]");
        scene_.sampleCount = int(*spp);
      }
      sp.ignore({"seed", "scramble", "dimension", "jitter", "strength", "resolution", "depth"});
      sp.checkAllUsed();
    } else {
      failAt(*n, "unexpected element inside <sensor>");
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// Integrator: only max_depth / rr_depth are read (from nested integrators too); the type is ignored.
// ---------------------------------------------------------------------------------------------------------

void Loader::parseIntegrator(const XmlElement& el) {
  checkAttributes(el, {"type", "id", "name"});
  requireAttr(el, "type");
  PropertyList props(el);
  std::vector<const XmlElement*> nested;
  collect(el, props, nested);
  if (auto d = props.optInt("max_depth")) {
    if (*d < -1 || *d > (1 << 20)) failAt(el, "max_depth must be -1 (unlimited) or in [0, 2^20]");
    scene_.maxDepth = int(*d);
  }
  if (auto d = props.optInt("rr_depth")) {
    if (*d < 0 || *d > (1 << 20)) failAt(el, "rr_depth must be in [0, 2^20]");
    scene_.rrDepth = int(*d);
  }
  if (props.getBool("hide_emitters", false)) warn(el, "hide_emitters is ignored (emitters stay visible)");
  // Everything else an integrator takes concerns the algorithm, which the job settings choose.
  props.ignoreAll();
  for (const XmlElement* n : nested) {
    if (n->name == "integrator") parseIntegrator(*n);  // inner settings win: they are read last
    else failAt(*n, "unexpected element inside <integrator>");
  }
}

// ---------------------------------------------------------------------------------------------------------
// Emitters
// ---------------------------------------------------------------------------------------------------------

Loader::AreaEmission Loader::parseAreaEmitter(const XmlElement& el) {
  checkAttributes(el, {"type", "id", "name"});
  const std::string type = requireAttr(el, "type");
  if (type != "area") failAt(el, "only 'area' emitters can be attached to a shape");
  PropertyList props(el);
  std::vector<const XmlElement*> nested;
  collect(el, props, nested);
  if (!nested.empty()) failAt(*nested.front(), "nested emitter parameters are not supported");
  AreaEmission out;
  if (props.has("radiance") && (props.find("radiance")->kind == Prop::Kind::Texture ||
                                props.find("radiance")->kind == Prop::Kind::Ref)) {
    out.texture = optTexture(props, "radiance");
    out.radiance = Color(1.0f);  // marks the mesh as emitting; Le comes from the texture
  } else {
    out.radiance = props.getColor("radiance", Color(1.0f));
    if (!out.radiance.isFinite() || out.radiance.r < 0 || out.radiance.g < 0 || out.radiance.b < 0)
      failAt(el, "radiance must be finite and non-negative");
  }
  props.ignore({"sampling_weight"});
  props.checkAllUsed();
  return out;
}

void Loader::parseEmitter(const XmlElement& el) {
  checkAttributes(el, {"type", "id", "name"});
  const std::string type = requireAttr(el, "type");
  if (type == "area") failAt(el, "an area emitter must be nested inside a <shape>");
  LightDesc light;
  if (type == "point") light.type = LightDesc::Type::Point;
  else if (type == "spot") light.type = LightDesc::Type::Spot;
  else if (type == "directional") light.type = LightDesc::Type::Directional;
  else if (type == "constant") light.type = LightDesc::Type::Constant;
  else failAt(el, "unknown or unsupported emitter type '" + type + "' (supported: area, point, spot, directional, constant)");
  PropertyList props(el);
  std::vector<const XmlElement*> nested;
  collect(el, props, nested);
  if (!nested.empty()) failAt(*nested.front(), "textured or nested emitter parameters are not supported");
  for (const char* n : {"intensity", "irradiance", "radiance"})
    if (props.has(n) && props.find(n)->kind == Prop::Kind::Texture) props.fail(*props.find(n), "textures are not supported here");
  const std::optional<Transform> toWorld = props.optTransform("to_world");
  const Transform T = toWorld.value_or(Transform());
  switch (light.type) {
    case LightDesc::Type::Point: {
      light.intensity = props.getColor("intensity", Color(1.0f));
      const auto pos = props.optVec("position");
      if (pos && toWorld) failAt(el, "give either 'position' or 'to_world', not both");
      light.position = pos ? *pos : T.point({0, 0, 0});
      break;
    }
    case LightDesc::Type::Spot: {
      light.intensity = props.getColor("intensity", Color(1.0f));
      light.position = T.point({0, 0, 0});
      light.direction = normalize(T.vector({0, 0, 1}));
      light.cutoffAngleDeg = float(props.getFloat("cutoff_angle", 20.0));
      light.beamWidthDeg = float(props.getFloat("beam_width", light.cutoffAngleDeg * 3.0 / 4.0));
      if (!(light.cutoffAngleDeg > 0 && light.cutoffAngleDeg < 180))  // the spot light's own range
        props.fail(*props.find("cutoff_angle"), "cutoff_angle must be in (0, 180) degrees");
      if (!(light.beamWidthDeg > 0)) props.fail(*props.find("beam_width"), "beam_width must be positive");
      if (light.beamWidthDeg > light.cutoffAngleDeg) light.beamWidthDeg = light.cutoffAngleDeg;
      break;
    }
    case LightDesc::Type::Directional: {
      light.intensity = props.getColor("irradiance", Color(1.0f));
      const auto dir = props.optVec("direction");
      if (dir && toWorld) failAt(el, "give either 'direction' or 'to_world', not both");
      const Vec3 d = dir ? *dir : T.vector({0, 0, 1});
      if (!(length(d) > 0)) failAt(el, "direction is zero");
      light.direction = normalize(d);
      break;
    }
    case LightDesc::Type::Constant:
      light.intensity = props.getColor("radiance", Color(1.0f));
      if (toWorld) failAt(el, "a constant emitter takes no to_world");
      break;
  }
  if (!light.intensity.isFinite() || light.intensity.r < 0 || light.intensity.g < 0 || light.intensity.b < 0)
    failAt(el, "emitted power must be finite and non-negative");
  if (!isFinite(light.position) || !isFinite(light.direction)) failAt(el, "emitter placement is not finite");
  props.ignore({"sampling_weight"});
  props.checkAllUsed();
  scene_.lights.push_back(light);
}

}  // namespace mitsuba

SceneDesc loadMitsubaScene(const std::string& path, const std::map<std::string, std::string>& defines,
                           const std::string& root) {
  mitsuba::Loader loader(defines, root);
  return loader.load(path);
}

}  // namespace mlt
