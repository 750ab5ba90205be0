// Stanford PLY reader (http://paulbourke.net/dataformats/ply/): header, then elements in header order.
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "common/scene/mesh_readers.h"
#include "common/scene/scene_error.h"

namespace mlt {
namespace {

enum class PlyType { I8, U8, I16, U16, I32, U32, F32, F64 };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::F32;
  bool isList = false;
  PlyType countType = PlyType::U8;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> props;
};

int typeSize(PlyType t) {
  switch (t) {
    case PlyType::I8: case PlyType::U8: return 1;
    case PlyType::I16: case PlyType::U16: return 2;
    case PlyType::I32: case PlyType::U32: case PlyType::F32: return 4;
    case PlyType::F64: return 8;
  }
  return 4;
}

bool parseType(const std::string& s, PlyType& t) {
  static const std::pair<const char*, PlyType> table[] = {
      {"char", PlyType::I8},    {"int8", PlyType::I8},     {"uchar", PlyType::U8},   {"uint8", PlyType::U8},
      {"short", PlyType::I16},  {"int16", PlyType::I16},   {"ushort", PlyType::U16}, {"uint16", PlyType::U16},
      {"int", PlyType::I32},    {"int32", PlyType::I32},   {"uint", PlyType::U32},   {"uint32", PlyType::U32},
      {"float", PlyType::F32},  {"float32", PlyType::F32}, {"double", PlyType::F64}, {"float64", PlyType::F64}};
  for (const auto& [name, type] : table)
    if (s == name) {
      t = type;
      return true;
    }
  return false;
}

// Reads scalar values from the body, in ascii or binary.
class PlyBody {
 public:
  PlyBody(const std::string& data, size_t pos, int line, int format, const std::string& path)
      : d_(data), pos_(pos), line_(line), format_(format), path_(path) {}

  double read(PlyType t) { return format_ == 0 ? readAscii() : readBinary(t); }

 private:
  [[noreturn]] void fail(const std::string& msg) const {
    if (format_ == 0) throw SceneError(path_, line_, msg);
    throw SceneError(path_, 0, msg + " (at byte " + std::to_string(pos_) + ")");
  }
  double readAscii() {
    while (pos_ < d_.size() && std::isspace((unsigned char)d_[pos_])) {
      if (d_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ >= d_.size()) fail("unexpected end of file in PLY data");
    size_t end = pos_;
    while (end < d_.size() && !std::isspace((unsigned char)d_[end])) ++end;
    const std::string tok = d_.substr(pos_, end - pos_);
    char* stop = nullptr;
    const double v = std::strtod(tok.c_str(), &stop);
    if (stop != tok.c_str() + tok.size()) fail("'" + tok + "' is not a number");
    pos_ = end;
    return v;
  }
  double readBinary(PlyType t) {
    const int n = typeSize(t);
    if (pos_ + n > d_.size()) fail("unexpected end of file in binary PLY data");
    unsigned char b[8];
    std::memcpy(b, d_.data() + pos_, n);
    pos_ += n;
    const bool fileBig = format_ == 2;
    const uint16_t probe = 1;
    const bool hostBig = *reinterpret_cast<const uint8_t*>(&probe) == 0;
    if (fileBig != hostBig)
      for (int i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    switch (t) {
      case PlyType::I8: { int8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::U8: { uint8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::I16: { int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::U16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::I32: { int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::U32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::F32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::F64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }

  const std::string& d_;
  size_t pos_;
  int line_;
  int format_;  // 0 ascii, 1 little endian, 2 big endian
  const std::string& path_;
};

int findProp(const PlyElement& e, std::initializer_list<const char*> names) {
  for (const char* n : names)
    for (size_t i = 0; i < e.props.size(); ++i)
      if (!e.props[i].isList && e.props[i].name == n) return int(i);
  return -1;
}

}  // namespace

MeshDesc readPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path, 0, "cannot open PLY file");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string data = ss.str();

  // ---- Header ----
  size_t pos = 0;
  int line = 0;
  auto nextLine = [&](std::string& out) {
    if (pos >= data.size()) return false;
    size_t end = data.find('\n', pos);
    if (end == std::string::npos) end = data.size();
    out = data.substr(pos, end - pos);
    if (!out.empty() && out.back() == '\r') out.pop_back();
    pos = std::min(end + 1, data.size());
    ++line;
    return true;
  };
  std::string l;
  if (!nextLine(l) || l != "ply") throw SceneError(path, 1, "not a PLY file (first line must be 'ply')");
  int format = -1;
  std::vector<PlyElement> elements;
  bool ended = false;
  while (nextLine(l)) {
    std::istringstream ls(l);
    std::string kw;
    ls >> kw;
    if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
    if (kw == "end_header") {
      ended = true;
      break;
    }
    if (kw == "format") {
      std::string f, v;
      ls >> f >> v;
      if (f == "ascii") format = 0;
      else if (f == "binary_little_endian") format = 1;
      else if (f == "binary_big_endian") format = 2;
      else throw SceneError(path, line, "unknown PLY format '" + f + "'");
    } else if (kw == "element") {
      PlyElement e;
      long long count = -1;
      ls >> e.name >> count;
      if (e.name.empty() || count < 0 || ls.fail()) throw SceneError(path, line, "malformed PLY element line '" + l + "'");
      if (size_t(count) > data.size()) throw SceneError(path, line, "PLY element count " + std::to_string(count) + " exceeds the file size");
      e.count = size_t(count);
      elements.push_back(e);
    } else if (kw == "property") {
      if (elements.empty()) throw SceneError(path, line, "PLY property before any element");
      PlyProperty p;
      std::string t;
      ls >> t;
      if (t == "list") {
        std::string ct, it;
        ls >> ct >> it >> p.name;
        p.isList = true;
        if (!parseType(ct, p.countType) || !parseType(it, p.type) || p.name.empty())
          throw SceneError(path, line, "malformed PLY list property '" + l + "'");
      } else {
        ls >> p.name;
        if (!parseType(t, p.type) || p.name.empty()) throw SceneError(path, line, "malformed PLY property '" + l + "'");
      }
      elements.back().props.push_back(p);
    } else {
      throw SceneError(path, line, "unknown PLY header keyword '" + kw + "'");
    }
  }
  if (!ended) throw SceneError(path, line, "PLY header has no end_header");
  if (format < 0) throw SceneError(path, line, "PLY header has no format line");

  // ---- Body ----
  MeshDesc mesh;
  mesh.name = path;
  PlyBody body(data, pos, line + 1, format, path);  // data starts on the line after end_header
  bool haveVertices = false;
  for (const PlyElement& e : elements) {
    const bool isVertex = e.name == "vertex", isFace = e.name == "face";
    int px = -1, py = -1, pz = -1, nx = -1, ny = -1, nz = -1, pu = -1, pv = -1, faceList = -1;
    if (isVertex) {
      px = findProp(e, {"x"}), py = findProp(e, {"y"}), pz = findProp(e, {"z"});
      if (px < 0 || py < 0 || pz < 0) throw SceneError(path, 0, "PLY vertex element lacks x, y or z");
      nx = findProp(e, {"nx"}), ny = findProp(e, {"ny"}), nz = findProp(e, {"nz"});
      pu = findProp(e, {"u", "s", "texture_u", "texture_s"});
      pv = findProp(e, {"v", "t", "texture_v", "texture_t"});
      haveVertices = true;
      mesh.positions.reserve(e.count);
    }
    if (isFace) {
      for (size_t i = 0; i < e.props.size(); ++i)
        if (e.props[i].isList && (e.props[i].name == "vertex_indices" || e.props[i].name == "vertex_index"))
          faceList = int(i);
      if (faceList < 0) throw SceneError(path, 0, "PLY face element has no vertex_indices list");
      if (!haveVertices) throw SceneError(path, 0, "PLY face element comes before the vertex element");
    }
    const bool hasNormals = nx >= 0 && ny >= 0 && nz >= 0, hasUv = pu >= 0 && pv >= 0;
    std::vector<double> vals(e.props.size());
    std::vector<uint32_t> poly;
    for (size_t r = 0; r < e.count; ++r) {
      for (size_t k = 0; k < e.props.size(); ++k) {
        const PlyProperty& p = e.props[k];
        if (!p.isList) {
          vals[k] = body.read(p.type);
          continue;
        }
        const double n = body.read(p.countType);
        if (!(n >= 0) || n != std::floor(n)) throw SceneError(path, 0, "PLY list has invalid length");
        const bool keep = isFace && int(k) == faceList;
        if (keep) poly.clear();
        for (size_t j = 0; j < size_t(n); ++j) {
          const double v = body.read(p.type);
          if (keep) {
            if (!(v >= 0) || v >= double(mesh.positions.size()) || v != std::floor(v))
              throw SceneError(path, 0, "PLY face " + std::to_string(r) + " has invalid vertex index " + std::to_string(v));
            poly.push_back(uint32_t(v));
          }
        }
        if (keep) {
          if (poly.size() < 3)
            throw SceneError(path, 0, "PLY face " + std::to_string(r) + " has fewer than 3 vertices");
          for (size_t j = 1; j + 1 < poly.size(); ++j) mesh.indices.insert(mesh.indices.end(), {poly[0], poly[j], poly[j + 1]});
        }
      }
      if (isVertex) {
        mesh.positions.push_back({float(vals[px]), float(vals[py]), float(vals[pz])});
        if (hasNormals) mesh.normals.push_back({float(vals[nx]), float(vals[ny]), float(vals[nz])});
        if (hasUv) mesh.uvs.push_back({float(vals[pu]), float(vals[pv])});
      }
    }
  }
  if (!haveVertices) throw SceneError(path, 0, "PLY file has no vertex element");
  return mesh;
}

}  // namespace mlt
