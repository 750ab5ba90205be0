// pbrt-v3 scene files, lexical level: tokens with their file and line, and a directive's parameter list
// ("type name" value | [values]). The semantics (directives -> SceneDesc) live in pbrt_loader.cpp.
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/scene/scene_error.h"

namespace mlt::pbrt {

struct Token {
  enum class Kind { Word, String, Number, Open, Close };
  Kind kind = Kind::Word;
  std::string text;   // the word, the string without quotes, or the number as written
  double number = 0;  // Number
  std::string file;
  int line = 0;
};

// Splits a file into tokens; '#' starts a comment to the end of the line. Throws SceneError naming the
// file and line for an unterminated string or a stray character.
std::vector<Token> tokenizeFile(const std::string& path);
std::vector<Token> tokenize(const std::string& text, const std::string& file);

[[noreturn]] inline void failAt(const Token& t, const std::string& what) { throw SceneError(t.file, t.line, what); }

// One "type name" parameter and its values.
struct Param {
  std::string type, name;
  std::vector<double> numbers;
  std::vector<std::string> strings;  // string, texture, bool ("true"/"false")
  Token where;                       // the "type name" token
  bool used = false;
};

// The parameter list of one directive. Typed getters check the declared type and the value count and
// mark the parameter used; checkAllUsed() refuses any parameter the loader did not read, naming it.
class ParamList {
 public:
  ParamList(std::string directive, Token where) : directive_(std::move(directive)), where_(std::move(where)) {}
  void add(Param p);

  bool has(const std::string& name) const { return params_.count(name) != 0; }
  const Param* find(const std::string& name) const;
  std::optional<double> optFloat(const std::string& name);
  double getFloat(const std::string& name, double def) { return optFloat(name).value_or(def); }
  std::optional<long long> optInt(const std::string& name);
  std::optional<std::string> optString(const std::string& name);
  bool getBool(const std::string& name, bool def);
  // rgb / color (3 numbers); `spectrum` and `blackbody` are refused (no spectral data).
  std::optional<Color> optColor(const std::string& name);
  std::optional<Vec3> optPoint(const std::string& name);  // point / point3 / vector / normal
  std::vector<double> numbers(const std::string& name, const std::vector<std::string>& types);
  // A texture reference ("texture name" "tex") or nullopt.
  std::optional<std::string> optTextureRef(const std::string& name);
  void ignore(std::initializer_list<const char*> names);
  void checkAllUsed() const;

  [[noreturn]] void fail(const Param& p, const std::string& what) const { failAt(p.where, what); }
  [[noreturn]] void fail(const std::string& what) const { failAt(where_, directive_ + ": " + what); }
  const Token& where() const { return where_; }
  const std::string& directive() const { return directive_; }

 private:
  Param* take(const std::string& name, std::initializer_list<const char*> types);
  std::string directive_;
  Token where_;
  std::map<std::string, Param> params_;
};

}  // namespace mlt::pbrt
