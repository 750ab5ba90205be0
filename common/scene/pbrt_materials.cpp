// pbrt-v3 front end: materials, textures and lights (conventions in pbrt_loader.h).
#include <cmath>
#include <filesystem>

#include "common/scene/material_tables.h"
#include "common/scene/pbrt_internal.h"
#include "common/scene/pbrt_loader.h"

namespace fs = std::filesystem;

namespace mlt::pbrt {

int Loader::defaultMaterial() {
  if (defaultMaterial_ >= 0) return defaultMaterial_;
  BsdfDesc d;
  d.type = BsdfDesc::Type::Diffuse;
  d.id = "<pbrt default matte>";
  d.reflectance = Color(0.5f);
  scene_.bsdfs.push_back(d);
  BsdfDesc two;
  two.type = BsdfDesc::Type::TwoSided;
  two.id = d.id;
  two.nested = int(scene_.bsdfs.size()) - 1;
  scene_.bsdfs.push_back(two);
  defaultMaterial_ = int(scene_.bsdfs.size()) - 1;
  return defaultMaterial_;
}

std::optional<TextureDesc> Loader::lookupTexture(const Param& ref, bool colour) {
  const std::string& name = ref.strings.at(0);
  auto& primary = colour ? colorTextures_ : floatTextures_;
  auto& other = colour ? floatTextures_ : colorTextures_;
  if (auto it = primary.find(name); it != primary.end()) return it->second;
  if (auto it = other.find(name); it != other.end()) return it->second;
  failAt(ref.where, "no texture named '" + name + "' (define it before use)");
}

TextureDesc Loader::colorParam(ParamList& p, const std::string& name, Color def) {
  if (const Param* q = p.find(name); q && q->type == "texture") {
    p.optTextureRef(name);
    return *lookupTexture(*q, true);
  }
  if (const Param* q = p.find(name); q && q->type == "float") {
    const float v = float(p.getFloat(name, 0));
    return TextureDesc(Color(v));
  }
  const Color c = p.optColor(name).value_or(def);
  if (!c.isFinite() || c.r < 0 || c.g < 0 || c.b < 0) p.fail(*p.find(name), "'" + name + "' must be finite and non-negative");
  return TextureDesc(c);
}

TextureDesc Loader::floatTexture(ParamList& p, const std::string& name, float def) {
  if (const Param* q = p.find(name); q && q->type == "texture") {
    p.optTextureRef(name);
    return *lookupTexture(*q, false);
  }
  return TextureDesc(Color(float(p.getFloat(name, def))));
}

namespace {
bool isBlack(const TextureDesc& t) { return t.isConstant() && t.value.isBlack(); }

// A roughness pair -> alpha (remapped as pbrt does), refusing anisotropy and textured roughness.
float readAlpha(ParamList& p, Loader*, float def, bool* smooth) {
  const bool hasU = p.has("uroughness"), hasV = p.has("vroughness");
  double r = def;
  auto constant = [&](const char* n) -> double {
    const Param* q = p.find(n);
    if (q && q->type == "texture") p.fail(*q, std::string("a textured '") + n + "' is not supported");
    return p.getFloat(n, def);
  };
  if (hasU || hasV) {
    const double u = constant("uroughness"), v = constant("vroughness");
    if (u != v) p.fail(*p.find(hasU ? "uroughness" : "vroughness"), "anisotropic roughness (uroughness != vroughness) is not supported");
    r = u;
    if (p.has("roughness")) p.fail(*p.find("roughness"), "give roughness or uroughness/vroughness, not both");
  } else if (p.has("roughness")) {
    r = constant("roughness");
  }
  if (!(r >= 0) || !std::isfinite(r)) p.fail("roughness must be finite and >= 0");
  const bool remap = p.getBool("remaproughness", true);
  *smooth = r == 0;
  return remap ? pbrtRoughnessToAlpha(float(r)) : float(r);
}
}  // namespace

int Loader::makeMaterial(ParamList& p, const std::string& type, const Token& where) {
  using T = BsdfDesc::Type;
  BsdfDesc d;
  d.id = "pbrt material '" + type + "' at " + at(where);
  bool twoSided = true;
  if (const Param* q = p.find("bumpmap")) p.fail(*q, "bump mapping is not supported");
  if (type == "matte") {
    d.type = T::Diffuse;
    d.reflectance = colorParam(p, "Kd", Color(0.5f));
    const TextureDesc sigma = floatTexture(p, "sigma", 0);
    if (!isBlack(sigma)) p.fail(*p.find("sigma"), "matte with sigma != 0 (Oren-Nayar) is not supported");
  } else if (type == "mirror") {
    d.type = T::Conductor;
    d.mirror = true;
    d.eta = Color(0.0f);
    d.k = Color(1.0f);
    d.extIOR = 1;
    d.specularReflectance = colorParam(p, "Kr", Color(0.9f));
  } else if (type == "glass") {
    twoSided = false;
    d.specularReflectance = colorParam(p, "Kr", Color(1.0f));
    d.specularTransmittance = colorParam(p, "Kt", Color(1.0f));
    double eta = 1.5;
    for (const char* n : {"eta", "index"})
      if (p.has(n)) {
        const Param* q = p.find(n);
        if (q->type == "texture") p.fail(*q, "a textured IOR is not supported");
        eta = p.getFloat(n, 1.5);
      }
    if (!(eta > 0)) p.fail("glass eta must be positive");
    d.intIOR = float(eta);
    d.extIOR = 1.0f;
    bool smooth = true;
    d.alpha = readAlpha(p, this, 0, &smooth);
    d.type = smooth ? T::Dielectric : T::RoughDielectric;
    d.distribution = MicrofacetType::GGX;
  } else if (type == "metal") {
    d.extIOR = 1;
    const auto cu = lookupConductor("Cu");
    for (const char* n : {"eta", "k"})
      if (const Param* q = p.find(n); q && q->type == "spectrum")
        p.fail(*q, std::string("metal '") + n + "' as a spectrum (e.g. an .spd file) is not supported; give an rgb");
    d.eta = p.optColor("eta").value_or(cu ? cu->first : Color(0.2f));
    d.k = p.optColor("k").value_or(cu ? cu->second : Color(3.9f));
    bool smooth = false;
    d.alpha = readAlpha(p, this, 0.01f, &smooth);
    d.type = smooth ? T::Conductor : T::RoughConductor;
    d.distribution = MicrofacetType::GGX;
  } else if (type == "plastic" || type == "uber") {
    // Only the cases that are exactly Lambertian map: pbrt's plastic and uber add an uncoupled glossy lobe
    // (and uber a specular and a transmissive one) that none of our BSDFs reproduces.
    d.type = T::Diffuse;
    d.reflectance = colorParam(p, "Kd", Color(0.25f));
    const TextureDesc ks = colorParam(p, "Ks", Color(0.25f));
    bool ok = isBlack(ks);
    if (type == "uber") {
      ok = ok && isBlack(colorParam(p, "Kr", Color(0.0f))) && isBlack(colorParam(p, "Kt", Color(0.0f)));
      const TextureDesc op = colorParam(p, "opacity", Color(1.0f));
      ok = ok && op.isConstant() && op.value.r == 1 && op.value.g == 1 && op.value.b == 1;
      p.ignore({"eta", "index"});
    }
    if (!ok)
      failAt(where, "Material \"" + type + "\": pbrt's " + type +
                        " has no equivalent among our BSDFs (only the Lambertian case Ks = 0" +
                        (type == "uber" ? std::string(", Kr = Kt = 0, opacity 1") : std::string()) +
                        " is supported); use matte, or a Mitsuba scene with plastic/roughplastic");
    p.ignore({"roughness", "uroughness", "vroughness", "remaproughness"});
  } else if (type == "substrate") {
    failAt(where, "Material \"substrate\": pbrt's Ashikhmin-Shirley substrate has no equivalent among our BSDFs");
  } else if (type == "" || type == "none") {
    failAt(where, "Material \"" + type + "\": interface materials (media boundaries) are not supported");
  } else {
    failAt(where, "Material: unsupported type '" + type + "' (supported: matte, mirror, glass, metal; plastic and "
                  "uber in their Lambertian case)");
  }
  p.ignore({"type"});
  p.checkAllUsed();
  scene_.bsdfs.push_back(d);
  int idx = int(scene_.bsdfs.size()) - 1;
  if (twoSided) {
    BsdfDesc two;
    two.type = T::TwoSided;
    two.id = d.id;
    two.nested = idx;
    scene_.bsdfs.push_back(two);
    idx = int(scene_.bsdfs.size()) - 1;
  }
  return idx;
}

void Loader::texture(const Token& where) {
  const std::string name = readString("a texture name");
  const std::string kind = readString("a texture type (spectrum or float)");
  const std::string cls = readString("a texture class");
  ParamList p = readParams("Texture \"" + name + "\" \"" + cls + "\"", where);
  if (kind != "spectrum" && kind != "color" && kind != "rgb" && kind != "float")
    failAt(where, "Texture: type must be spectrum or float, not '" + kind + "'");
  const bool colour = kind != "float";
  auto param = [&](const char* n, float def) { return colour ? colorParam(p, n, Color(def)) : floatTexture(p, n, def); };
  const std::string mapping = p.optString("mapping").value_or("uv");
  if (mapping != "uv") p.fail(*p.find("mapping"), "Texture: only the uv mapping is supported");
  const double su = p.getFloat("uscale", 1), sv = p.getFloat("vscale", 1), du = p.getFloat("udelta", 0),
               dv = p.getFloat("vdelta", 0);
  TextureDesc t;
  if (cls == "imagemap") {
    const auto file = p.optString("filename");
    if (!file) p.fail("imagemap needs a \"string filename\"");
    const std::string ext = lower(fs::path(*file).extension().string());
    if (ext != ".png" && ext != ".jpg" && ext != ".jpeg")
      p.fail(*p.find("filename"), "imagemap: only PNG and JPEG images are supported, not '" + ext + "'");
    t.type = TextureDesc::Type::Bitmap;
    t.filename = resolve(p.find("filename")->where, *file, "image file");
    t.srgb = p.getBool("gamma", true);  // pbrt-v3: 8-bit PNGs are sRGB-encoded by default
    const std::string wrap = p.optString("wrap").value_or("repeat");
    if (wrap != "repeat") p.fail(*p.find("wrap"), "imagemap: only wrap \"repeat\" is supported");
    if (p.getFloat("scale", 1) != 1) p.fail(*p.find("scale"), "imagemap: scale != 1 is not supported");
    if (p.getBool("invert", false)) p.fail(*p.find("invert"), "imagemap: invert is not supported");
    p.ignore({"maxanisotropy", "trilinear", "filter"});
    // pbrt's t runs up the image; ours runs down: v' = 1 - (sv v + dv).
    t.uvScale = {float(su), float(-sv)};
    t.uvOffset = {float(du), float(1 - dv)};
  } else if (cls == "checkerboard") {
    if (p.optInt("dimension").value_or(2) != 2) p.fail(*p.find("dimension"), "checkerboard: only dimension 2");
    const TextureDesc a = param("tex1", 1), b = param("tex2", 0);
    if (!a.isConstant() || !b.isConstant()) p.fail("checkerboard: tex1 and tex2 must be constants");
    const std::string aa = p.optString("aamode").value_or("closedform");
    if (aa != "none")
      scene_.warnings.push_back(at(where) + ": checkerboard aamode '" + aa + "' is not reproduced (point-sampled)");
    t.type = TextureDesc::Type::Checkerboard;
    t.color0 = a.value;  // pbrt: tex1 where floor(s) + floor(t) is even
    t.color1 = b.value;
    // pbrt's cells are 1 x 1 in (s, t); ours are 1/2 x 1/2 in uv'.
    t.uvScale = {float(su / 2), float(sv / 2)};
    t.uvOffset = {float(du / 2), float(dv / 2)};
  } else if (cls == "constant") {
    t = param("value", 1);
  } else if (cls == "scale") {
    TextureDesc a = param("tex1", 1), b = param("tex2", 1);
    if (!a.isConstant()) std::swap(a, b);
    if (!a.isConstant()) p.fail("scale: one of tex1, tex2 must be a constant");
    if (b.isConstant()) t = TextureDesc(a.value * b.value);
    else if (b.type == TextureDesc::Type::Checkerboard) {
      t = b;
      t.color0 = a.value * b.color0;
      t.color1 = a.value * b.color1;
    } else {
      p.fail("scale: scaling an imagemap is not supported");
    }
  } else {
    failAt(where, "Texture: unsupported class '" + cls + "' (supported: imagemap, checkerboard, constant, scale)");
  }
  if (cls != "imagemap" && cls != "checkerboard" && (su != 1 || sv != 1 || du != 0 || dv != 0))
    p.fail("Texture: uscale/vscale/udelta/vdelta only apply to imagemap and checkerboard");
  p.checkAllUsed();
  (colour ? colorTextures_ : floatTextures_)[name] = t;
}

void Loader::lightSource(const Token& where) {
  const std::string type = readString("a light type");
  ParamList p = readParams("LightSource \"" + type + "\"", where);
  const Color scale = p.optColor("scale").value_or(Color(1.0f));
  LightDesc l;
  if (type == "point") {
    l.type = LightDesc::Type::Point;
    l.intensity = p.optColor("I").value_or(Color(1.0f)) * scale;
    l.position = gs_.ctm.point(p.optPoint("from").value_or(Vec3(0.0f)));
  } else if (type == "spot") {
    l.type = LightDesc::Type::Spot;
    l.intensity = p.optColor("I").value_or(Color(1.0f)) * scale;
    const Vec3 from = p.optPoint("from").value_or(Vec3(0.0f)), to = p.optPoint("to").value_or(Vec3(0, 0, 1));
    l.position = gs_.ctm.point(from);
    const Vec3 dir = gs_.ctm.vector(to - from);
    if (!(length(dir) > 0)) p.fail("spot: from and to coincide");
    l.direction = normalize(dir);
    const double cone = p.getFloat("coneangle", 30), delta = p.getFloat("conedelta", 5);
    if (!(cone > 0 && cone < 90)) p.fail("spot: coneangle must be in (0, 90)");
    if (!(delta >= 0 && delta <= cone)) {
      const std::string msg = "spot: conedelta must be in [0, coneangle]";
      if (const Param* q = p.find("conedelta")) p.fail(*q, msg);
      p.fail(msg);
    }
    // pbrt-v3: full intensity inside coneangle - conedelta, its quartic falloff to zero at coneangle.
    l.cutoffAngleDeg = float(cone);
    l.beamWidthDeg = float(cone - delta);
    l.spotFalloff = LightDesc::SpotFalloff::PbrtQuartic;
  } else if (type == "distant") {
    l.type = LightDesc::Type::Directional;
    l.intensity = p.optColor("L").value_or(Color(1.0f)) * scale;
    const Vec3 from = p.optPoint("from").value_or(Vec3(0.0f)), to = p.optPoint("to").value_or(Vec3(0, 0, 1));
    const Vec3 dir = gs_.ctm.vector(to - from);  // light travels from -> to
    if (!(length(dir) > 0)) p.fail("distant: from and to coincide");
    l.direction = normalize(dir);
  } else if (type == "infinite") {
    if (const Param* q = p.find("mapname")) p.fail(*q, "infinite: environment maps are not supported (constant only)");
    l.type = LightDesc::Type::Constant;
    l.intensity = p.optColor("L").value_or(Color(1.0f)) * scale;
    p.ignore({"nsamples", "samples"});
  } else {
    failAt(where, "LightSource: unsupported type '" + type + "' (supported: point, spot, distant, infinite)");
  }
  if (!l.intensity.isFinite() || l.intensity.r < 0 || l.intensity.g < 0 || l.intensity.b < 0)
    p.fail("the light's intensity must be finite and non-negative");
  p.checkAllUsed();
  if (currentObject_) failAt(where, "LightSource inside ObjectBegin is not supported");
  scene_.lights.push_back(l);
}

}  // namespace mlt::pbrt
