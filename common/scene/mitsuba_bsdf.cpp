// Mitsuba BSDF and texture plugins -> BsdfDesc / TextureDesc. Defaults follow Mitsuba: dielectric
// int_ior = bk7 (1.5046), ext_ior = air (1.000277); plastic int_ior = polypropylene (1.49); conductor
// material = Cu in 0.6 scenes and "none" (ideal mirror) in 3.x scenes; distribution = beckmann,
// alpha = 0.1.
#include <algorithm>
#include <cctype>
#include <filesystem>

#include "common/scene/material_tables.h"
#include "common/scene/mitsuba_internal.h"

namespace mlt::mitsuba {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// An IOR given as a number or as a name from Mitsuba's table.
float readIor(PropertyList& props, const char* name, float def) {
  const Prop* p = props.find(name);
  if (!p) return def;
  float v = 0;
  if (p->kind == Prop::Kind::String) {
    const auto ior = lookupIor(p->s);
    if (!ior) props.fail(*p, "unknown IOR material '" + p->s + "' (known: " + knownIorNames() + ")");
    v = *ior;
  } else {
    v = float(props.getFloat(name, def));
  }
  if (!(v > 0)) props.fail(*p, std::string(name) + " must be positive");
  return v;
}

MicrofacetType readDistribution(PropertyList& props) {
  const auto d = props.optString("distribution");
  if (!d) return MicrofacetType::Beckmann;
  const std::string s = lower(*d);
  if (s == "beckmann") return MicrofacetType::Beckmann;
  if (s == "ggx") return MicrofacetType::GGX;
  props.fail(*props.find("distribution"), "unsupported microfacet distribution '" + *d + "' (supported: beckmann, ggx)");
}

bool isTextureProp(PropertyList& props, const char* name) {
  const Prop* p = props.find(name);
  return p && (p->kind == Prop::Kind::Texture || p->kind == Prop::Kind::Ref);
}

float readAlpha(PropertyList& props) {
  const bool hasU = props.has("alpha_u"), hasV = props.has("alpha_v");
  float alpha = 0.1f;
  if (hasU || hasV) {
    if (props.has("alpha")) props.fail(*props.find("alpha"), "give either alpha or alpha_u/alpha_v, not both");
    if (!hasU || !hasV) props.fail(*props.find(hasU ? "alpha_u" : "alpha_v"), "alpha_u and alpha_v must be given together");
    const double u = props.getFloat("alpha_u", 0.1), v = props.getFloat("alpha_v", 0.1);
    if (u != v)
      props.fail(*props.find("alpha_v"), "anisotropic roughness (alpha_u = " + std::to_string(u) + " != alpha_v = " +
                                             std::to_string(v) + ") is not supported");
    alpha = float(u);
  } else if (props.has("alpha")) {
    alpha = float(props.getFloat("alpha", 0.1));
  }
  if (!(alpha > 0) || !(alpha <= 4)) props.fail(*props.find(props.has("alpha") ? "alpha" : "alpha_u"), "alpha must be in (0, 4]");
  return alpha;
}

void requireNonNegative(PropertyList& props, const char* name, const Color& c) {
  if (c.r < 0 || c.g < 0 || c.b < 0) props.fail(*props.find(name), std::string(name) + " must be non-negative");
}

Color readColor(PropertyList& props, const char* name, Color def) {
  const Color c = props.getColor(name, def);
  if (props.has(name)) requireNonNegative(props, name, c);
  return c;
}

// A roughconductor's / roughdielectric's alpha: a float, or a texture (its luminance at the hit's uv).
void readAlphaOrTexture(Loader& L, PropertyList& props, BsdfDesc& d) {
  for (const char* n : {"alpha_u", "alpha_v"})
    if (isTextureProp(props, n)) props.fail(*props.find(n), std::string("a textured ") + n + " (anisotropic) is not supported");
  if (isTextureProp(props, "alpha")) {
    d.alphaTexture = L.optTexture(props, "alpha");
    d.alpha = 0.1f;  // unused while the texture is set
    return;
  }
  d.alpha = readAlpha(props);
}

// A colour parameter Mitsuba lets a texture drive: colour, nested <texture> or <ref> to a texture.
TextureDesc readColorTexture(Loader& L, PropertyList& props, const char* name, Color def) {
  if (!props.has(name)) return TextureDesc(def);
  return *L.optTexture(props, name);
}

// Conductor optics: `material` preset, or explicit eta and k.
void readConductor(Loader& L, PropertyList& props, BsdfDesc& d) {
  const bool hasEta = props.has("eta"), hasK = props.has("k");
  if (hasEta || hasK) {
    if (props.has("material")) props.fail(*props.find("material"), "give either material or eta/k, not both");
    if (!hasEta || !hasK) props.fail(*props.find(hasEta ? "eta" : "k"), "eta and k must be given together");
    d.eta = props.getColor("eta", Color(0.0f));
    d.k = props.getColor("k", Color(1.0f));
    requireNonNegative(props, "eta", d.eta);
    requireNonNegative(props, "k", d.k);
  } else {
    const std::string def = L.majorVersion() < 2 ? "Cu" : "none";
    const std::string m = props.optString("material").value_or(def);
    if (lower(m) == "none") {
      d.mirror = true;
      d.eta = Color(0.0f);
      d.k = Color(1.0f);
    } else {
      const auto ek = lookupConductor(m);
      if (!ek) props.fail(*props.find("material"), "conductor material '" + m + "' is not in our table (known: " +
                                                       knownConductorNames() + "); give eta and k as <rgb>");
      d.eta = ek->first;
      d.k = ek->second;
    }
  }
  // 0.6's ext_eta; 3.x conductors take eta relative to vacuum.
  d.extIOR = readIor(props, "ext_eta", L.majorVersion() < 2 ? 1.000277f : 1.0f);
  d.specularReflectance = readColorTexture(L, props, "specular_reflectance", Color(1.0f));
}

// uv' = scale * uv + offset from 0.6's uscale/vscale/uoffset/voffset and 3.x's to_uv.
void readUvTransform(PropertyList& props, TextureDesc& t) {
  t.uvScale = {float(props.getFloat("uscale", 1)), float(props.getFloat("vscale", 1))};
  t.uvOffset = {float(props.getFloat("uoffset", 0)), float(props.getFloat("voffset", 0))};
  if (auto T = props.optTransform("to_uv")) {
    const auto& m = T->m;
    if (m[0][1] != 0 || m[1][0] != 0 || m[0][2] != 0 || m[1][2] != 0)
      props.fail(*props.find("to_uv"), "to_uv may only scale and translate u and v");
    // to_uv after the 0.6 parameters: uv'' = S2 (S1 uv + o1) + o2.
    t.uvOffset = {float(m[0][0] * t.uvOffset.x + m[0][3]), float(m[1][1] * t.uvOffset.y + m[1][3])};
    t.uvScale = {float(m[0][0] * t.uvScale.x), float(m[1][1] * t.uvScale.y)};
  }
}

}  // namespace

int Loader::bsdfFromRef(const XmlElement& ref) {
  checkAttributes(ref, {"id", "name"});
  const std::string& id = requireAttr(ref, "id");
  auto it = namedBsdfs_.find(id);
  if (it != namedBsdfs_.end()) return it->second;
  if (idKinds_.count(id)) failAt(ref, "id '" + id + "' is a " + idKinds_[id] + ", not a bsdf");
  failAt(ref, "no bsdf with id '" + id + "' (it must be declared before it is referenced)");
}

std::optional<TextureDesc> Loader::optTexture(PropertyList& props, const std::string& name) {
  if (!props.has(name)) return std::nullopt;
  const Prop* p = props.find(name);
  if (p->kind == Prop::Kind::Texture) {
    TextureDesc t = parseTexture(*p->el);
    if (const XmlAttribute* id = p->el->find("id")) {
      registerId(*p->el, "texture");
      namedTextures_[id->value] = t;
    }
    return t;
  }
  if (p->kind == Prop::Kind::Ref) {
    auto it = namedTextures_.find(p->s);
    if (it == namedTextures_.end()) props.fail(*p, "no texture with id '" + p->s + "' (declare it before use)");
    return it->second;
  }
  TextureDesc t;
  t.type = TextureDesc::Type::Constant;
  t.value = props.getColor(name, Color(0.5f));
  requireNonNegative(props, name.c_str(), t.value);
  return t;
}

TextureDesc Loader::parseTexture(const XmlElement& el) {
  checkAttributes(el, {"type", "id", "name"});
  const std::string type = requireAttr(el, "type");
  PropertyList props(el);
  std::vector<const XmlElement*> nested;
  collect(el, props, nested);
  if (!nested.empty()) failAt(*nested.front(), "nested plugins inside a texture are not supported");
  TextureDesc t;
  if (type == "bitmap") {
    t.type = TextureDesc::Type::Bitmap;
    const auto file = props.optString("filename");
    if (!file) failAt(el, "bitmap texture needs a filename");
    const std::string ext = lower(std::filesystem::path(*file).extension().string());
    if (ext != ".png" && ext != ".jpg" && ext != ".jpeg")
      props.fail(*props.find("filename"), "only PNG and JPEG bitmaps are supported, not '" + ext + "'");
    t.filename = resolveFile(*props.find("filename")->el, *file, "bitmap texture file");
    t.srgb = !props.getBool("raw", false);
    if (auto g = props.optFloat("gamma")) {  // Mitsuba 0.6: -1 = sRGB, 1 = linear
      if (*g == 1) t.srgb = false;
      else if (*g == -1) t.srgb = true;
      else if (*g == 2.2) { t.srgb = true; warn(el, "gamma 2.2 is decoded as sRGB"); }
      else props.fail(*props.find("gamma"), "only gamma -1 (sRGB), 2.2 or 1 (linear) are supported");
    }
    for (const char* w : {"wrap_mode", "wrap_mode_u", "wrap_mode_v"})
      if (auto m = props.optString(w); m && lower(*m) != "repeat")
        warn(el, std::string(w) + " '" + *m + "' is replaced by repeat");
    props.ignore({"filter_type", "max_anisotropy", "cache", "filter"});
  } else if (type == "checkerboard") {
    t.type = TextureDesc::Type::Checkerboard;
    t.color0 = readColor(props, "color0", Color(0.4f));
    t.color1 = readColor(props, "color1", Color(0.2f));
  } else {
    failAt(el, "unknown or unsupported texture type '" + type + "' (supported: bitmap, checkerboard)");
  }
  readUvTransform(props, t);
  props.checkAllUsed();
  return t;
}

int Loader::parseBsdf(const XmlElement& el) {
  checkAttributes(el, {"type", "id", "name"});
  const std::string type = requireAttr(el, "type");
  BsdfDesc d;
  if (const XmlAttribute* id = el.find("id")) d.id = id->value;
  else d.id = "<anonymous " + type + " bsdf at " + el.file + ":" + std::to_string(el.line) + ">";
  PropertyList props(el);
  std::vector<const XmlElement*> nested;
  collect(el, props, nested);

  using T = BsdfDesc::Type;
  if (type == "diffuse") {
    d.type = T::Diffuse;
    d.reflectance = optTexture(props, "reflectance").value_or(TextureDesc{});
    if (!props.has("reflectance")) d.reflectance.value = Color(0.5f);
  } else if (type == "twosided") {
    d.type = T::TwoSided;
    for (const auto& [name, p] : props.takeKind(Prop::Kind::Ref)) nested.push_back(p->el);
    if (nested.size() != 1 || (nested[0]->name != "bsdf" && nested[0]->name != "ref"))
      failAt(el, "twosided needs exactly one nested <bsdf> or <ref> (different front/back BSDFs are not supported)");
    d.nested = nested[0]->name == "bsdf" ? parseBsdf(*nested[0]) : bsdfFromRef(*nested[0]);
    if (nested[0]->name == "bsdf" && nested[0]->has("id")) {
      registerId(*nested[0], "bsdf");
      namedBsdfs_[nested[0]->find("id")->value] = d.nested;
    }
    nested.clear();
  } else if (type == "dielectric" || type == "thindielectric" || type == "roughdielectric") {
    d.type = type == "dielectric" ? T::Dielectric : type == "thindielectric" ? T::ThinDielectric : T::RoughDielectric;
    d.intIOR = readIor(props, "int_ior", 1.5046f);
    d.extIOR = readIor(props, "ext_ior", 1.000277f);
    d.specularReflectance = readColorTexture(*this, props, "specular_reflectance", Color(1.0f));
    d.specularTransmittance = readColorTexture(*this, props, "specular_transmittance", Color(1.0f));
    if (d.type == T::RoughDielectric) {
      d.distribution = readDistribution(props);
      readAlphaOrTexture(*this, props, d);
      props.ignore({"sample_visible"});
    }
  } else if (type == "conductor" || type == "roughconductor") {
    d.type = type == "conductor" ? T::Conductor : T::RoughConductor;
    readConductor(*this, props, d);
    if (d.type == T::RoughConductor) {
      d.distribution = readDistribution(props);
      readAlphaOrTexture(*this, props, d);
      props.ignore({"sample_visible"});
    }
  } else if (type == "plastic" || type == "roughplastic") {
    d.type = type == "plastic" ? T::Plastic : T::RoughPlastic;
    d.reflectance = optTexture(props, "diffuse_reflectance").value_or(TextureDesc{});
    if (!props.has("diffuse_reflectance")) d.reflectance.value = Color(0.5f);
    d.specularReflectance = readColorTexture(*this, props, "specular_reflectance", Color(1.0f));
    d.intIOR = readIor(props, "int_ior", 1.49f);
    d.extIOR = readIor(props, "ext_ior", 1.000277f);
    d.nonlinear = props.getBool("nonlinear", false);
    if (d.type == T::RoughPlastic) {
      d.distribution = readDistribution(props);
      if (isTextureProp(props, "alpha"))
        props.fail(*props.find("alpha"), "a textured alpha is not supported on roughplastic (nor in Mitsuba 3)");
      d.alpha = readAlpha(props);
      props.ignore({"sample_visible"});
    }
  } else {
    failAt(el, "unknown or unsupported BSDF type '" + type +
                   "' (supported: diffuse, twosided, dielectric, thindielectric, roughdielectric, conductor, "
                   "roughconductor, plastic, roughplastic)");
  }
  if (!nested.empty()) failAt(*nested.front(), "unexpected element inside " + describe(el));
  props.checkAllUsed();
  scene_.bsdfs.push_back(d);
  return int(scene_.bsdfs.size()) - 1;
}

}  // namespace mlt::mitsuba
