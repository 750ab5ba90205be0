// Mitsuba XML parameter handling: the typed property list of one plugin element (<float>, <rgb>,
// <transform>, ...), strict number parsing and the transform grammar. Parameter names are normalized from
// Mitsuba 0.6 camelCase to 3.x snake_case (toWorld -> to_world, intIOR -> int_ior), so every lookup uses
// the 3.x spelling. Every accessor marks the parameter used; checkAllUsed() turns anything left over into
// an "unknown parameter" error, so the set of accepted names is exactly what the plugin code reads or
// explicitly ignore()s.
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/core/transform.h"
#include "common/core/vec.h"
#include "common/scene/scene_error.h"
#include "common/scene/xml_parser.h"

namespace mlt {

// "toWorld" -> "to_world", "intIOR" -> "int_ior"; snake_case is unchanged.
std::string mitsubaName(const std::string& name);

// "<bsdf type="diffuse">" / "<float name="fov">" for messages.
std::string describe(const XmlElement& el);

[[noreturn]] void failAt(const XmlElement& el, const std::string& msg);

// Strict parsing: the whole string must be one finite number (or integer).
double parseNumber(const XmlElement& el, const std::string& attr, const std::string& text);
long long parseInteger(const XmlElement& el, const std::string& attr, const std::string& text);
// Comma- and/or whitespace-separated finite numbers.
std::vector<double> parseNumberList(const XmlElement& el, const std::string& attr, const std::string& text);

// The value of a required attribute (error naming the element if missing).
const std::string& requireAttr(const XmlElement& el, const std::string& attr);
// Error if `el` has an attribute not in `allowed`.
void checkAttributes(const XmlElement& el, std::initializer_list<const char*> allowed);

// <transform>: children lookat, matrix, translate, rotate, scale composed in document order (M = new * M).
Transform parseTransformElement(const XmlElement& el);

struct Prop {
  enum class Kind { Float, Integer, Boolean, String, Vec, Color, Transform, Texture, Ref };
  Kind kind = Kind::Float;
  const XmlElement* el = nullptr;  // the defining element (for messages; nested <texture> for Kind::Texture)
  bool isPoint = false;            // Vec: <point> rather than <vector>
  double f = 0;
  long long i = 0;
  bool b = false;
  std::string s;                   // String; Ref: the referenced id
  Vec3 v;
  Color c;
  Transform t;
  bool used = false;
};

class PropertyList {
 public:
  explicit PropertyList(const XmlElement& owner) : owner_(&owner) {}

  // Parses one property element (<float>, <integer>, <boolean>, <string>, <point>, <vector>, <rgb>, <srgb>,
  // <spectrum>, <transform>, or a named <texture>/<ref>). Returns false if `child` is not a property.
  bool addFromElement(const XmlElement& child);

  bool has(const std::string& name) const { return props_.count(name) != 0; }
  const Prop* find(const std::string& name);  // marks used; nullptr if absent

  double getFloat(const std::string& name, double def);
  std::optional<double> optFloat(const std::string& name);
  long long getInt(const std::string& name, long long def);
  std::optional<long long> optInt(const std::string& name);
  bool getBool(const std::string& name, bool def);
  std::optional<std::string> optString(const std::string& name);
  std::optional<Vec3> optVec(const std::string& name);  // <point> or <vector>
  std::optional<Color> optColor(const std::string& name);  // rgb / srgb / spectrum / float
  Color getColor(const std::string& name, Color def) { return optColor(name).value_or(def); }
  std::optional<Transform> optTransform(const std::string& name);

  // Every property of `kind` (e.g. named <ref>s), in document order; marks them used.
  std::vector<std::pair<std::string, const Prop*>> takeKind(Prop::Kind kind);

  // Accepts these parameters without using them (they do not change the rendered image).
  void ignore(std::initializer_list<const char*> names);
  void ignoreAll();
  // Throws "unknown parameter" for the first property nobody read.
  void checkAllUsed() const;

  [[noreturn]] void fail(const Prop& p, const std::string& msg) const { failAt(*p.el, msg); }
  const XmlElement& owner() const { return *owner_; }

 private:
  Prop& typed(const std::string& name, std::initializer_list<Prop::Kind> kinds, const char* what);
  const XmlElement* owner_;
  std::map<std::string, Prop> props_;
};

}  // namespace mlt
