// Private to the Mitsuba front end: the loader's state shared by mitsuba_loader.cpp (scene structure,
// sensor, emitters, integrator), mitsuba_shapes.cpp and mitsuba_bsdf.cpp (BSDFs and textures).
#pragma once
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "common/scene/mitsuba_props.h"
#include "common/scene/scene_desc.h"
#include "common/scene/xml_parser.h"

namespace mlt::mitsuba {

class Loader {
 public:
  // `root`: when non-empty, every file the scene reads must lie inside it (common/scene/scene_files.h).
  Loader(const std::map<std::string, std::string>& defines, std::string root) : defines_(defines), root_(std::move(root)) {}
  SceneDesc load(const std::string& path);

  // Splits a plugin element's children into properties and nested plugin elements (<bsdf>, <emitter>,
  // <film>, unnamed <ref>, ...). Unknown child tags are errors.
  void collect(const XmlElement& el, PropertyList& props, std::vector<const XmlElement*>& nested) const;

  // --- mitsuba_bsdf.cpp ---
  int parseBsdf(const XmlElement& el);                       // appends to scene_.bsdfs, returns index
  TextureDesc parseTexture(const XmlElement& el);
  // A reflectance parameter: colour, nested <texture>, or <ref> to a named texture.
  std::optional<TextureDesc> optTexture(PropertyList& props, const std::string& name);
  int bsdfFromRef(const XmlElement& ref);                     // index of a named BSDF

  // --- mitsuba_shapes.cpp ---
  void parseShape(const XmlElement& el);

  // --- mitsuba_loader.cpp ---
  void parseEmitter(const XmlElement& el);   // top-level (non-area) emitters
  void parseSensor(const XmlElement& el);
  void parseIntegrator(const XmlElement& el);
  struct AreaEmission {
    Color radiance;
    std::optional<TextureDesc> texture;  // a textured radiance
  };
  AreaEmission parseAreaEmitter(const XmlElement& el);
  // Resolves a file name relative to the referencing file, then the main scene's folder (confined to
  // root_ if set: resolveSceneFile); records it. Errors name the element's file and line.
  std::string resolveFile(const XmlElement& el, const std::string& filename, const char* what);
  void warn(const XmlElement& el, const std::string& msg);
  int defaultBsdf();
  int majorVersion() const { return majorVersion_; }

 private:
  void processSceneChildren(XmlElement& root, int depth);
  void substitute(XmlElement& el);
  std::string substituteValue(const XmlElement& el, const XmlAttribute& a) const;
  void registerId(const XmlElement& el, const std::string& kind);

  std::map<std::string, std::string> defines_;  // command line: win over <default>
  std::map<std::string, std::string> params_;   // the effective $name table
  std::vector<std::unique_ptr<XmlElement>> docs_;  // keeps every parsed document alive
  std::set<std::string> includeStack_;
  std::string mainFile_, mainDir_;
  std::string root_;  // confinement directory (empty: none)
  int majorVersion_ = 3;
  bool haveSensor_ = false;
  int defaultBsdf_ = -1;

 public:
  SceneDesc scene_;
  std::map<std::string, int> namedBsdfs_;
  std::map<std::string, TextureDesc> namedTextures_;
  std::map<std::string, std::string> idKinds_;  // id -> "bsdf" / "texture" / ... for messages
};

}  // namespace mlt::mitsuba
