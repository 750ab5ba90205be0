// Private to the pbrt-v3 front end: the loader's state shared by pbrt_loader.cpp (token stream, scene
// structure, camera, shapes) and pbrt_materials.cpp (materials, textures, lights).
#pragma once
#include <algorithm>
#include <cctype>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/core/transform.h"
#include "common/scene/pbrt_tokens.h"
#include "common/scene/scene_desc.h"

namespace mlt::pbrt {

inline std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}
inline std::string at(const Token& t) { return t.file + ":" + std::to_string(t.line); }

struct AreaLightState {
  Color L{1.0f};
  bool twoSided = false;
};

struct GraphicsState {
  Transform ctm;
  bool reverseOrientation = false;
  int material = -1;  // index into SceneDesc::bsdfs; -1 = pbrt's default (matte, Kd 0.5)
  std::optional<AreaLightState> areaLight;
};

class Loader {
 public:
  // `root`: when non-empty, every file the scene reads must lie inside it (common/scene/scene_files.h).
  explicit Loader(std::string root = {}) : root_(std::move(root)) {}
  SceneDesc load(const std::string& path);

 private:
  // --- token stream ---
  const Token& next(const char* what);
  const Token* peek() const { return pos_ < tokens_.size() ? &tokens_[pos_] : nullptr; }
  std::string readString(const char* what);
  double readNumber(const char* what);
  std::vector<double> readNumbers(size_t n, const char* what);  // n numbers, bracketed or not
  ParamList readParams(const std::string& directive, const Token& where);
  void include(const Token& where);

  // --- directives ---
  void directive(const Token& t);
  void shape(const Token& where);
  void material(ParamList& params, const std::string& type, const Token& where);
  int makeMaterial(ParamList& params, const std::string& type, const Token& where);
  void texture(const Token& where);
  void lightSource(const Token& where);
  void camera(const Token& where);
  void addMesh(MeshDesc mesh, bool analytic, const Token& where);

  // Colour / float parameters that may be textures.
  TextureDesc colorParam(ParamList& p, const std::string& name, Color def);
  TextureDesc floatTexture(ParamList& p, const std::string& name, float def);
  std::optional<TextureDesc> lookupTexture(const Param& ref, bool colour);
  int defaultMaterial();
  std::string resolve(const Token& where, const std::string& file, const char* what);

  std::vector<Token> tokens_;
  size_t pos_ = 0;
  SceneDesc scene_;
  std::string mainDir_;
  std::string root_;  // confinement directory (empty: none)
  std::set<std::string> includeStack_;
  std::vector<GraphicsState> stack_;
  std::vector<Transform> transformStack_;
  GraphicsState gs_;
  std::map<std::string, Transform> namedCoordSys_;
  std::map<std::string, int> namedMaterials_;
  std::map<std::string, TextureDesc> colorTextures_, floatTextures_;
  std::map<std::string, std::vector<MeshDesc>> objects_;
  std::vector<MeshDesc>* currentObject_ = nullptr;
  bool inWorld_ = false, haveCamera_ = false, haveIntegrator_ = false;
  int defaultMaterial_ = -1;
};

}  // namespace mlt::pbrt
