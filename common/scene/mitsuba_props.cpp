#include "common/scene/mitsuba_props.h"

#include "common/core/clip.h"
#include "common/scene/camera_transform.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace mlt {

std::string mitsubaName(const std::string& name) {
  std::string out;
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (std::isupper((unsigned char)c)) {
      if (i > 0 && (std::islower((unsigned char)name[i - 1]) || std::isdigit((unsigned char)name[i - 1]))) out += '_';
      out += char(std::tolower((unsigned char)c));
    } else {
      out += c;
    }
  }
  return out;
}

std::string describe(const XmlElement& el) {
  std::string s = "<" + el.name;
  for (const char* a : {"type", "name", "id"})
    if (const XmlAttribute* at = el.find(a)) s += std::string(" ") + a + "=\"" + clipForMessage(at->value, 64) + "\"";
  return s + ">";
}

void failAt(const XmlElement& el, const std::string& msg) { throw SceneError(el.file, el.line, describe(el) + ": " + msg); }

static std::string trimmed(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace((unsigned char)s[a])) ++a;
  while (b > a && std::isspace((unsigned char)s[b - 1])) --b;
  return s.substr(a, b - a);
}

double parseNumber(const XmlElement& el, const std::string& attr, const std::string& text) {
  const std::string t = trimmed(text);
  if (t.empty()) failAt(el, "attribute '" + attr + "' is empty, expected a number");
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (end != t.c_str() + t.size()) failAt(el, "'" + t + "' in attribute '" + attr + "' is not a number");
  if (!std::isfinite(v) || (errno == ERANGE && std::fabs(v) > 1))
    failAt(el, "'" + t + "' in attribute '" + attr + "' is not a finite number");
  return v;
}

long long parseInteger(const XmlElement& el, const std::string& attr, const std::string& text) {
  const std::string t = trimmed(text);
  if (t.empty()) failAt(el, "attribute '" + attr + "' is empty, expected an integer");
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(t.c_str(), &end, 10);
  if (end != t.c_str() + t.size() || errno == ERANGE)
    failAt(el, "'" + t + "' in attribute '" + attr + "' is not an integer");
  return v;
}

std::vector<double> parseNumberList(const XmlElement& el, const std::string& attr, const std::string& text) {
  std::vector<double> out;
  std::string tok;
  auto flush = [&] {
    if (!tok.empty()) out.push_back(parseNumber(el, attr, tok));
    tok.clear();
  };
  for (char c : text) {
    if (c == ',' || std::isspace((unsigned char)c)) flush();
    else tok += c;
  }
  flush();
  return out;
}

const std::string& requireAttr(const XmlElement& el, const std::string& attr) {
  const XmlAttribute* a = el.find(attr);
  if (!a) failAt(el, "missing attribute '" + attr + "'");
  return a->value;
}

void checkAttributes(const XmlElement& el, std::initializer_list<const char*> allowed) {
  for (const XmlAttribute& a : el.attributes) {
    bool ok = false;
    for (const char* n : allowed) ok = ok || a.name == n;
    if (!ok) throw SceneError(el.file, a.line, describe(el) + ": unknown attribute '" + a.name + "'");
  }
}

// ---------------------------------------------------------------------------------------------------------
// Transforms
// ---------------------------------------------------------------------------------------------------------

static Vec3 parseVec3(const XmlElement& el, const std::string& attr) {
  const std::vector<double> v = parseNumberList(el, attr, requireAttr(el, attr));
  if (v.size() != 3) failAt(el, "attribute '" + attr + "' needs 3 numbers, got " + std::to_string(v.size()));
  return {float(v[0]), float(v[1]), float(v[2])};
}

// x/y/z attributes (each defaulting to `def`) or a `value` with 1 or 3 numbers.
static Vec3 parseXyzOrValue(const XmlElement& el, float def, bool allowSingle) {
  if (el.has("value")) {
    if (el.has("x") || el.has("y") || el.has("z")) failAt(el, "give either 'value' or x/y/z, not both");
    const std::vector<double> v = parseNumberList(el, "value", el.find("value")->value);
    if (v.size() == 1 && allowSingle) return Vec3(float(v[0]));
    if (v.size() != 3) failAt(el, "attribute 'value' needs 3 numbers");
    return {float(v[0]), float(v[1]), float(v[2])};
  }
  Vec3 r(def);
  const char* names[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i)
    if (const XmlAttribute* a = el.find(names[i])) r[i] = float(parseNumber(el, names[i], a->value));
  return r;
}

Transform parseTransformElement(const XmlElement& el) {
  checkAttributes(el, {"name"});
  Transform M;
  for (const XmlElement& c : el.children) {
    Transform T;
    try {
      if (c.name == "translate") {
        checkAttributes(c, {"x", "y", "z", "value"});
        T = Transform::translate(parseXyzOrValue(c, 0.0f, false));
      } else if (c.name == "scale") {
        checkAttributes(c, {"x", "y", "z", "value"});
        T = Transform::scale(parseXyzOrValue(c, 1.0f, true));
      } else if (c.name == "rotate") {
        checkAttributes(c, {"x", "y", "z", "value", "angle"});
        const Vec3 axis = parseXyzOrValue(c, 0.0f, false);
        const double angle = parseNumber(c, "angle", requireAttr(c, "angle"));
        if (!(length(axis) > 0)) failAt(c, "rotation axis is zero (give x, y, z or value)");
        T = Transform::rotate(axis, angle);
      } else if (c.name == "matrix") {
        checkAttributes(c, {"value"});
        const std::vector<double> v = parseNumberList(c, "value", requireAttr(c, "value"));
        if (v.size() != 16) failAt(c, "matrix needs 16 numbers (row-major 4x4), got " + std::to_string(v.size()));
        for (int i = 0; i < 4; ++i)
          for (int j = 0; j < 4; ++j) T.m[i][j] = v[4 * i + j];
      } else if (c.name == "lookat") {
        checkAttributes(c, {"origin", "target", "up"});
        const Vec3 o = parseVec3(c, "origin"), t = parseVec3(c, "target");
        Vec3 up;
        if (c.has("up")) up = parseVec3(c, "up");
        else if (length(t - o) > 0) up = Frame(normalize(t - o)).s;  // Mitsuba 3: any vector orthogonal to the view
        if (const std::string problem = lookAtProblem(o, t, up); !problem.empty()) failAt(c, problem);
        T = Transform::lookAt(o, t, up);
      } else {
        failAt(c, "unknown transform operation (expected translate, rotate, scale, matrix or lookat)");
      }
    } catch (const SceneError&) {
      throw;
    } catch (const std::exception& e) {
      failAt(c, e.what());
    }
    M = T * M;
    if (!M.isFinite()) failAt(c, "transform is not finite");
  }
  return M;
}

// ---------------------------------------------------------------------------------------------------------
// Property list
// ---------------------------------------------------------------------------------------------------------

static float srgbToLinear(double v) {
  return float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
}

static Color parseColorValue(const XmlElement& el, bool srgb) {
  const std::string& text = requireAttr(el, "value");
  const std::string t = trimmed(text);
  if (srgb && !t.empty() && t[0] == '#') {
    if (t.size() != 7) failAt(el, "hex colour must be #rrggbb");
    Color c;
    for (int i = 0; i < 3; ++i) {
      char* end = nullptr;
      const std::string h = t.substr(1 + 2 * i, 2);
      const long v = std::strtol(h.c_str(), &end, 16);
      if (end != h.c_str() + 2) failAt(el, "bad hex colour '" + t + "'");
      c[i] = srgbToLinear(v / 255.0);
    }
    return c;
  }
  const std::vector<double> v = parseNumberList(el, "value", text);
  Color c;
  if (v.size() == 1) c = Color(float(v[0]));
  else if (v.size() == 3) c = Color(float(v[0]), float(v[1]), float(v[2]));
  else failAt(el, "colour needs 1 or 3 numbers, got " + std::to_string(v.size()));
  if (srgb)
    for (int i = 0; i < 3; ++i) c[i] = srgbToLinear(c[i]);
  return c;
}

// Uniform spectra only: "0.5", or "400:0.5, 700:0.5" with all values equal.
static Color parseSpectrumValue(const XmlElement& el) {
  if (el.has("filename")) failAt(el, "spectra from files are not supported (use a uniform value or <rgb>)");
  const std::string& text = requireAttr(el, "value");
  std::vector<double> values;
  std::string tok;
  bool sawColon = false;
  auto flush = [&] {
    if (tok.empty()) return;
    const size_t colon = tok.find(':');
    if (colon != std::string::npos) {
      sawColon = true;
      parseNumber(el, "value", tok.substr(0, colon));  // wavelength must be a number
      values.push_back(parseNumber(el, "value", tok.substr(colon + 1)));
    } else {
      values.push_back(parseNumber(el, "value", tok));
    }
    tok.clear();
  };
  for (char c : text) {
    if (c == ',' || std::isspace((unsigned char)c)) flush();
    else tok += c;
  }
  flush();
  if (values.empty()) failAt(el, "empty spectrum");
  for (double v : values)
    if (v != values[0])
      failAt(el, std::string("only uniform spectra are supported (") +
                     (sawColon ? "wavelength:value pairs" : "values") + " differ); use <rgb>");
  return Color(float(values[0]));
}

bool PropertyList::addFromElement(const XmlElement& c) {
  static const char* kPropTags[] = {"float", "integer", "boolean", "string", "point", "vector",
                                    "rgb",   "srgb",    "spectrum", "transform"};
  bool isProp = false;
  for (const char* t : kPropTags) isProp = isProp || c.name == t;
  const bool namedObject = (c.name == "texture" || c.name == "ref") && c.has("name");
  if (!isProp && !namedObject) return false;

  Prop p;
  p.el = &c;
  const std::string name = mitsubaName(requireAttr(c, "name"));
  if (c.name == "float") {
    checkAttributes(c, {"name", "value"});
    p.kind = Prop::Kind::Float;
    p.f = parseNumber(c, "value", requireAttr(c, "value"));
  } else if (c.name == "integer") {
    checkAttributes(c, {"name", "value"});
    p.kind = Prop::Kind::Integer;
    p.i = parseInteger(c, "value", requireAttr(c, "value"));
  } else if (c.name == "boolean") {
    checkAttributes(c, {"name", "value"});
    p.kind = Prop::Kind::Boolean;
    std::string v = trimmed(requireAttr(c, "value"));
    std::transform(v.begin(), v.end(), v.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
    if (v == "true") p.b = true;
    else if (v == "false") p.b = false;
    else failAt(c, "'" + v + "' is not a boolean (true or false)");
  } else if (c.name == "string") {
    checkAttributes(c, {"name", "value"});
    p.kind = Prop::Kind::String;
    p.s = requireAttr(c, "value");
  } else if (c.name == "point" || c.name == "vector") {
    checkAttributes(c, {"name", "value", "x", "y", "z"});
    p.kind = Prop::Kind::Vec;
    p.isPoint = c.name == "point";
    if (!c.has("value") && !c.has("x") && !c.has("y") && !c.has("z")) failAt(c, "needs 'value' or x/y/z");
    p.v = parseXyzOrValue(c, 0.0f, false);
  } else if (c.name == "rgb" || c.name == "srgb") {
    checkAttributes(c, {"name", "value", "intent"});
    p.kind = Prop::Kind::Color;
    p.c = parseColorValue(c, c.name == "srgb");
  } else if (c.name == "spectrum") {
    checkAttributes(c, {"name", "value", "filename", "intent"});
    p.kind = Prop::Kind::Color;
    p.c = parseSpectrumValue(c);
  } else if (c.name == "transform") {
    p.kind = Prop::Kind::Transform;
    p.t = parseTransformElement(c);
  } else if (c.name == "texture") {
    p.kind = Prop::Kind::Texture;
  } else {  // named ref
    checkAttributes(c, {"name", "id"});
    p.kind = Prop::Kind::Ref;
    p.s = requireAttr(c, "id");
  }
  if (props_.count(name)) failAt(c, "parameter '" + name + "' is given twice");
  props_.emplace(name, p);
  return true;
}

const Prop* PropertyList::find(const std::string& name) {
  auto it = props_.find(name);
  if (it == props_.end()) return nullptr;
  it->second.used = true;
  return &it->second;
}

Prop& PropertyList::typed(const std::string& name, std::initializer_list<Prop::Kind> kinds, const char* what) {
  Prop& p = props_.at(name);
  p.used = true;
  for (Prop::Kind k : kinds)
    if (p.kind == k) return p;
  fail(p, "parameter '" + name + "' must be " + what);
}

std::optional<double> PropertyList::optFloat(const std::string& name) {
  if (!has(name)) return std::nullopt;
  const Prop& p = typed(name, {Prop::Kind::Float, Prop::Kind::Integer}, "a <float>");
  return p.kind == Prop::Kind::Float ? p.f : double(p.i);
}
double PropertyList::getFloat(const std::string& name, double def) { return optFloat(name).value_or(def); }

std::optional<long long> PropertyList::optInt(const std::string& name) {
  if (!has(name)) return std::nullopt;
  return typed(name, {Prop::Kind::Integer}, "an <integer>").i;
}
long long PropertyList::getInt(const std::string& name, long long def) { return optInt(name).value_or(def); }

bool PropertyList::getBool(const std::string& name, bool def) {
  if (!has(name)) return def;
  return typed(name, {Prop::Kind::Boolean}, "a <boolean>").b;
}

std::optional<std::string> PropertyList::optString(const std::string& name) {
  if (!has(name)) return std::nullopt;
  return typed(name, {Prop::Kind::String}, "a <string>").s;
}

std::optional<Vec3> PropertyList::optVec(const std::string& name) {
  if (!has(name)) return std::nullopt;
  return typed(name, {Prop::Kind::Vec}, "a <point> or <vector>").v;
}

std::optional<Color> PropertyList::optColor(const std::string& name) {
  if (!has(name)) return std::nullopt;
  const Prop& p = typed(name, {Prop::Kind::Color, Prop::Kind::Float, Prop::Kind::Integer},
                        "a colour (<rgb>, <spectrum> or <float>)");
  if (p.kind == Prop::Kind::Color) return p.c;
  return Color(float(p.kind == Prop::Kind::Float ? p.f : double(p.i)));
}

std::optional<Transform> PropertyList::optTransform(const std::string& name) {
  if (!has(name)) return std::nullopt;
  return typed(name, {Prop::Kind::Transform}, "a <transform>").t;
}

void PropertyList::ignore(std::initializer_list<const char*> names) {
  for (const char* n : names) {
    auto it = props_.find(n);
    if (it != props_.end()) it->second.used = true;
  }
}

std::vector<std::pair<std::string, const Prop*>> PropertyList::takeKind(Prop::Kind kind) {
  std::vector<std::pair<std::string, const Prop*>> out;
  for (auto& [name, p] : props_)
    if (p.kind == kind) {
      p.used = true;
      out.emplace_back(name, &p);
    }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.second->el->line < b.second->el->line; });
  return out;
}

void PropertyList::ignoreAll() {
  for (auto& kv : props_) kv.second.used = true;
}

void PropertyList::checkAllUsed() const {
  // Report in document order (by line) so the first problem is named first.
  const Prop* first = nullptr;
  std::string firstName;
  for (const auto& [name, p] : props_)
    if (!p.used && (!first || p.el->line < first->el->line)) {
      first = &p;
      firstName = name;
    }
  if (first)
    failAt(*first->el, "unknown or unsupported parameter '" + firstName + "' of " + describe(*owner_) +
                           " (declared on line " + std::to_string(owner_->line) + ")");
}

}  // namespace mlt
