#include "common/scene/pbrt_tokens.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace mlt::pbrt {

std::vector<Token> tokenizeFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw SceneError(path, 0, "cannot open pbrt file");
  std::stringstream ss;
  ss << f.rdbuf();
  return tokenize(ss.str(), path);
}

std::vector<Token> tokenize(const std::string& s, const std::string& file) {
  std::vector<Token> out;
  int line = 1;
  size_t i = 0;
  const size_t n = s.size();
  while (i < n) {
    const char c = s[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (c == '#') {
      while (i < n && s[i] != '\n') ++i;
    } else if (c == '[' || c == ']') {
      Token t;
      t.kind = c == '[' ? Token::Kind::Open : Token::Kind::Close;
      t.text = std::string(1, c);
      t.file = file;
      t.line = line;
      out.push_back(t);
      ++i;
    } else if (c == '"') {
      Token t;
      t.kind = Token::Kind::String;
      t.file = file;
      t.line = line;
      ++i;
      while (i < n && s[i] != '"') {
        if (s[i] == '\n') throw SceneError(file, t.line, "unterminated string");
        if (s[i] == '\\' && i + 1 < n) {
          ++i;
          const char e = s[i];
          t.text.push_back(e == 'n' ? '\n' : e == 't' ? '\t' : e);
        } else {
          t.text.push_back(s[i]);
        }
        ++i;
      }
      if (i >= n) throw SceneError(file, t.line, "unterminated string");
      ++i;
      out.push_back(t);
    } else if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.') {
      Token t;
      t.kind = Token::Kind::Number;
      t.file = file;
      t.line = line;
      const size_t start = i;
      while (i < n && !std::isspace(static_cast<unsigned char>(s[i])) && s[i] != '[' && s[i] != ']' && s[i] != '"' &&
             s[i] != '#')
        ++i;
      t.text = s.substr(start, i - start);
      char* end = nullptr;
      t.number = std::strtod(t.text.c_str(), &end);
      if (end != t.text.c_str() + t.text.size() || !std::isfinite(t.number))
        throw SceneError(file, line, "malformed number '" + t.text + "'");
      out.push_back(t);
    } else if (std::isalpha(static_cast<unsigned char>(c))) {
      Token t;
      t.kind = Token::Kind::Word;
      t.file = file;
      t.line = line;
      const size_t start = i;
      while (i < n && (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '_')) ++i;
      t.text = s.substr(start, i - start);
      out.push_back(t);
    } else {
      throw SceneError(file, line, std::string("unexpected character '") + c + "'");
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------
// Parameter lists
// ---------------------------------------------------------------------------------------------------
namespace {
std::string canonicalType(const std::string& t) {
  if (t == "point3") return "point";
  if (t == "normal3") return "normal";
  if (t == "vector3") return "vector";
  if (t == "color") return "rgb";
  return t;
}
}  // namespace

void ParamList::add(Param p) {
  p.type = canonicalType(p.type);
  static const char* known[] = {"float", "integer", "string", "bool", "texture", "point", "normal",
                                "vector", "point2", "vector2", "rgb", "spectrum", "blackbody", "xyz"};
  bool ok = false;
  for (const char* k : known) ok = ok || p.type == k;
  if (!ok) failAt(p.where, "unknown parameter type '" + p.type + "' of '" + p.name + "'");
  if (params_.count(p.name)) failAt(p.where, "parameter '" + p.name + "' given twice");
  const std::string name = p.name;
  params_.emplace(name, std::move(p));
}

const Param* ParamList::find(const std::string& name) const {
  auto it = params_.find(name);
  return it == params_.end() ? nullptr : &it->second;
}

Param* ParamList::take(const std::string& name, std::initializer_list<const char*> types) {
  auto it = params_.find(name);
  if (it == params_.end()) return nullptr;
  Param& p = it->second;
  bool ok = false;
  std::string list;
  for (const char* t : types) {
    ok = ok || p.type == t;
    list += (list.empty() ? "" : " or ") + std::string(t);
  }
  if (!ok) fail(p, directive_ + ": parameter '" + name + "' must be " + list + ", not " + p.type);
  p.used = true;
  return &p;
}

std::optional<double> ParamList::optFloat(const std::string& name) {
  Param* p = take(name, {"float"});
  if (!p) return std::nullopt;
  if (p->numbers.size() != 1) fail(*p, directive_ + ": '" + name + "' needs exactly one value");
  return p->numbers[0];
}

std::optional<long long> ParamList::optInt(const std::string& name) {
  Param* p = take(name, {"integer"});
  if (!p) return std::nullopt;
  if (p->numbers.size() != 1 || p->numbers[0] != std::floor(p->numbers[0]))
    fail(*p, directive_ + ": '" + name + "' needs exactly one integer");
  return static_cast<long long>(p->numbers[0]);
}

std::optional<std::string> ParamList::optString(const std::string& name) {
  Param* p = take(name, {"string"});
  if (!p) return std::nullopt;
  if (p->strings.size() != 1) fail(*p, directive_ + ": '" + name + "' needs exactly one string");
  return p->strings[0];
}

bool ParamList::getBool(const std::string& name, bool def) {
  Param* p = take(name, {"bool"});
  if (!p) return def;
  if (p->strings.size() != 1 || (p->strings[0] != "true" && p->strings[0] != "false"))
    fail(*p, directive_ + ": '" + name + "' needs one \"true\" or \"false\"");
  return p->strings[0] == "true";
}

std::optional<Color> ParamList::optColor(const std::string& name) {
  const Param* q = find(name);
  if (q && (q->type == "spectrum" || q->type == "blackbody" || q->type == "xyz"))
    fail(*q, directive_ + ": " + q->type + " values are not supported for '" + name + "'; give an rgb");
  Param* p = take(name, {"rgb"});
  if (!p) return std::nullopt;
  if (p->numbers.size() != 3) fail(*p, directive_ + ": rgb '" + name + "' needs three values");
  return Color(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2]));
}

std::optional<Vec3> ParamList::optPoint(const std::string& name) {
  Param* p = take(name, {"point", "vector", "normal"});
  if (!p) return std::nullopt;
  if (p->numbers.size() != 3) fail(*p, directive_ + ": '" + name + "' needs three values");
  return Vec3(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2]));
}

std::vector<double> ParamList::numbers(const std::string& name, const std::vector<std::string>& types) {
  auto it = params_.find(name);
  if (it == params_.end()) return {};
  bool ok = false;
  for (const std::string& t : types) ok = ok || it->second.type == t;
  if (!ok) fail(it->second, directive_ + ": parameter '" + name + "' has the wrong type " + it->second.type);
  it->second.used = true;
  return it->second.numbers;
}

std::optional<std::string> ParamList::optTextureRef(const std::string& name) {
  auto it = params_.find(name);
  if (it == params_.end() || it->second.type != "texture") return std::nullopt;
  Param& p = it->second;
  p.used = true;
  if (p.strings.size() != 1) fail(p, directive_ + ": texture '" + name + "' needs one texture name");
  return p.strings[0];
}

void ParamList::ignore(std::initializer_list<const char*> names) {
  for (const char* n : names) {
    auto it = params_.find(n);
    if (it != params_.end()) it->second.used = true;
  }
}

void ParamList::checkAllUsed() const {
  const Param* first = nullptr;
  for (const auto& [name, p] : params_)
    if (!p.used && (!first || p.where.line < first->where.line)) first = &p;
  if (first)
    failAt(first->where, directive_ + ": unknown or unsupported parameter '" + first->type + " " + first->name + "'");
}

}  // namespace mlt::pbrt
