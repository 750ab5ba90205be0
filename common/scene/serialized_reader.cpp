// Mitsuba's `serialized` mesh format (0.6 and 3.x, file format versions 3 and 4), little-endian:
//
//   file      := shape* dictionary
//   shape     := uint16 0x041C, uint16 version (3 | 4), zlib stream of a record
//   record    := uint32 flags
//                [version 4: UTF-8 name, null-terminated]
//                uint64 vertexCount, uint64 triangleCount
//                positions [3 * vertexCount]                      float or double (flags 0x1000 / 0x2000)
//                normals   [3 * vertexCount]  if flags & 0x0001
//                texcoords [2 * vertexCount]  if flags & 0x0002
//                colors    [3 * vertexCount]  if flags & 0x0008  (read and dropped: we have no vertex colours)
//                indices   [3 * triangleCount] uint32 (uint64 if vertexCount > 2^32 - 1; refused here)
//                flags & 0x0010: the mesh asks for face normals (Mitsuba then ignores vertex normals)
//   dictionary := offset of each shape's header from the start of the file (version 4: uint64 each,
//                version 3: uint32 each), then uint32 shapeCount, at the very end of the file.
//
// Every read is bounds-checked: a truncated file, a bad dictionary, a corrupt zlib stream or a record
// that ends early is a SceneError naming the file and the shape index. Counts are checked against what
// the compressed bytes can possibly hold (zlib expands at most ~1032:1) before anything is allocated.
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <vector>

#include "common/scene/mesh_readers.h"
#include "common/scene/scene_error.h"

namespace mlt {

namespace {

constexpr uint16_t kHeader = 0x041C;
constexpr uint32_t kHasNormals = 0x0001, kHasTexcoords = 0x0002, kHasColors = 0x0008, kFaceNormals = 0x0010,
                   kSingle = 0x1000, kDouble = 0x2000;

template <typename T>
T readLE(const unsigned char* p) {
  T v{};
  for (size_t i = 0; i < sizeof(T); ++i) v = T(v | (T(p[i]) << (8 * i)));
  return v;
}

// Inflates one shape's record on demand from the file's bytes [begin, end).
class Inflater {
 public:
  Inflater(const std::string& where, const unsigned char* begin, size_t size) : where_(where) {
    std::memset(&z_, 0, sizeof(z_));
    if (inflateInit(&z_) != Z_OK) throw SceneError(where_, 0, "zlib initialisation failed");
    z_.next_in = const_cast<unsigned char*>(begin);
    z_.avail_in = uInt(std::min<size_t>(size, std::numeric_limits<uInt>::max()));
    compressed_ = size;
  }
  ~Inflater() { inflateEnd(&z_); }
  Inflater(const Inflater&) = delete;
  Inflater& operator=(const Inflater&) = delete;

  // The most uncompressed bytes the remaining input could produce (deflate's ratio is below 1032:1).
  uint64_t maxRemaining() const { return uint64_t(compressed_) * 1100 + 4096; }

  void read(void* out, size_t n, const char* what) {
    z_.next_out = static_cast<unsigned char*>(out);
    while (n > 0) {
      const size_t chunk = std::min<size_t>(n, 1u << 30);
      z_.avail_out = uInt(chunk);
      while (z_.avail_out > 0) {
        if (ended_) throw SceneError(where_, 0, std::string("record ends early (truncated) while reading ") + what);
        const int r = ::inflate(&z_, Z_NO_FLUSH);
        if (r == Z_STREAM_END) {
          ended_ = true;
        } else if (r == Z_BUF_ERROR || (r == Z_OK && z_.avail_in == 0 && z_.avail_out > 0)) {
          throw SceneError(where_, 0, std::string("compressed data is truncated while reading ") + what);
        } else if (r != Z_OK) {
          throw SceneError(where_, 0, std::string("corrupt compressed data while reading ") + what + " (zlib: " +
                                          (z_.msg ? z_.msg : "error " + std::to_string(r)) + ")");
        }
      }
      n -= chunk;
    }
  }
  // The record must end here; inflating to the end also checks zlib's Adler-32 of the whole record.
  void finish() {
    unsigned char extra;
    z_.next_out = &extra;
    z_.avail_out = 1;
    while (!ended_) {
      const int r = ::inflate(&z_, Z_NO_FLUSH);
      if (r == Z_STREAM_END) ended_ = true;
      else if (z_.avail_out == 0) throw SceneError(where_, 0, "unexpected bytes after the indices (corrupt record)");
      else if (r != Z_OK) throw SceneError(where_, 0, std::string("corrupt or truncated compressed data at the end of the record") +
                                                       (z_.msg ? std::string(" (zlib: ") + z_.msg + ")" : std::string()));
      else if (z_.avail_in == 0) throw SceneError(where_, 0, "compressed data is truncated at the end of the record");
    }
  }
  template <typename T>
  T get(const char* what) {
    unsigned char b[sizeof(T)];
    read(b, sizeof(T), what);
    return readLE<T>(b);
  }

 private:
  std::string where_;
  z_stream z_;
  size_t compressed_ = 0;
  bool ended_ = false;
};

// Reads n * dim reals stored as float or double.
std::vector<double> readReals(Inflater& in, uint64_t count, bool dbl, const char* what) {
  const size_t bytes = size_t(count) * (dbl ? 8 : 4);
  std::vector<unsigned char> raw(bytes);
  in.read(raw.data(), bytes, what);
  std::vector<double> v(static_cast<size_t>(count));
  for (size_t i = 0; i < v.size(); ++i) {
    if (dbl) {
      const uint64_t u = readLE<uint64_t>(&raw[8 * i]);
      double d;
      std::memcpy(&d, &u, 8);
      v[i] = d;
    } else {
      const uint32_t u = readLE<uint32_t>(&raw[4 * i]);
      float f;
      std::memcpy(&f, &u, 4);
      v[i] = f;
    }
    if (!std::isfinite(v[i])) throw std::runtime_error(std::string("non-finite value in ") + what);
  }
  return v;
}

}  // namespace

MeshDesc readSerialized(const std::string& path, int shapeIndex, bool* faceNormalsHint) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw SceneError(path, 0, "cannot open serialized mesh file");
  std::vector<unsigned char> data((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const std::string shapeWhere = path + " (shape_index " + std::to_string(shapeIndex) + ")";
  if (data.size() < 4 + 4) throw SceneError(path, 0, "file too short to be a serialized mesh (truncated?)");
  const uint16_t header = readLE<uint16_t>(&data[0]), version = readLE<uint16_t>(&data[2]);
  if (header != kHeader) throw SceneError(path, 0, "not a Mitsuba serialized mesh (bad header)");
  if (version != 3 && version != 4)
    throw SceneError(path, 0, "unsupported serialized format version " + std::to_string(version) + " (supported: 3, 4)");

  // The dictionary at the end of the file.
  const uint32_t count = readLE<uint32_t>(&data[data.size() - 4]);
  const size_t entry = version == 4 ? 8 : 4;
  if (count == 0 || uint64_t(count) * entry + 4 > data.size() - 4)
    throw SceneError(path, 0, "bad shape dictionary at the end of the file (shape count " + std::to_string(count) +
                                  "; truncated or corrupt?)");
  if (shapeIndex < 0 || uint32_t(shapeIndex) >= count)
    throw SceneError(path, 0, "shape_index " + std::to_string(shapeIndex) + " is out of range: the file holds " +
                                  std::to_string(count) + " shape(s)");
  const size_t dictStart = data.size() - 4 - size_t(count) * entry;
  auto offsetOf = [&](uint32_t i) -> uint64_t {
    const unsigned char* p = &data[dictStart + size_t(i) * entry];
    return version == 4 ? readLE<uint64_t>(p) : readLE<uint32_t>(p);
  };
  const uint64_t begin = offsetOf(uint32_t(shapeIndex));
  const uint64_t end = uint32_t(shapeIndex) + 1 < count ? offsetOf(uint32_t(shapeIndex) + 1) : dictStart;
  if (begin + 4 > dictStart || end > dictStart || end < begin + 4)
    throw SceneError(shapeWhere, 0, "bad offset in the shape dictionary (truncated or corrupt file)");
  if (readLE<uint16_t>(&data[begin]) != kHeader || readLE<uint16_t>(&data[begin + 2]) != version)
    throw SceneError(shapeWhere, 0, "the shape's record does not start with the serialized header (corrupt file)");

  Inflater in(shapeWhere, &data[begin + 4], size_t(end - begin - 4));
  const uint32_t flags = in.get<uint32_t>("flags");
  const bool dbl = (flags & kDouble) != 0;
  if (dbl == ((flags & kSingle) != 0))
    throw SceneError(shapeWhere, 0, "flags must set exactly one of single (0x1000) and double (0x2000) precision");
  std::string name;
  if (version == 4) {
    for (;;) {
      const char c = char(in.get<uint8_t>("the shape name"));
      if (c == 0) break;
      if (name.size() > 4096) throw SceneError(shapeWhere, 0, "shape name longer than 4096 bytes (corrupt?)");
      name.push_back(c);
    }
  }
  const uint64_t nv = in.get<uint64_t>("the vertex count"), nt = in.get<uint64_t>("the triangle count");
  if (nv > std::numeric_limits<uint32_t>::max())
    throw SceneError(shapeWhere, 0, "more than 2^32 - 1 vertices (64-bit indices) are not supported");
  const uint64_t real = dbl ? 8 : 4;
  const uint64_t perVertex = real * (3 + ((flags & kHasNormals) ? 3 : 0) + ((flags & kHasTexcoords) ? 2 : 0) +
                                     ((flags & kHasColors) ? 3 : 0));
  if (nt > std::numeric_limits<uint32_t>::max() ||
      double(nv) * double(perVertex) + double(nt) * 12.0 > double(in.maxRemaining()))
    throw SceneError(shapeWhere, 0, "vertex count " + std::to_string(nv) + " / triangle count " + std::to_string(nt) +
                                        " cannot fit in the compressed record (corrupt or truncated)");
  if (nv == 0 || nt == 0) throw SceneError(shapeWhere, 0, "the mesh has no vertices or no triangles");

  MeshDesc mesh;
  mesh.name = name;
  try {
    const auto p = readReals(in, 3 * nv, dbl, "positions");
    mesh.positions.resize(size_t(nv));
    for (size_t i = 0; i < nv; ++i) mesh.positions[i] = Vec3(float(p[3 * i]), float(p[3 * i + 1]), float(p[3 * i + 2]));
    if (flags & kHasNormals) {
      const auto n = readReals(in, 3 * nv, dbl, "normals");
      mesh.normals.resize(size_t(nv));
      for (size_t i = 0; i < nv; ++i) mesh.normals[i] = Vec3(float(n[3 * i]), float(n[3 * i + 1]), float(n[3 * i + 2]));
    }
    if (flags & kHasTexcoords) {
      const auto t = readReals(in, 2 * nv, dbl, "texcoords");
      mesh.uvs.resize(size_t(nv));
      for (size_t i = 0; i < nv; ++i) mesh.uvs[i] = Vec2(float(t[2 * i]), float(t[2 * i + 1]));
    }
    if (flags & kHasColors) readReals(in, 3 * nv, dbl, "vertex colors");
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    throw SceneError(shapeWhere, 0, e.what());
  }
  std::vector<unsigned char> raw(size_t(nt) * 12);
  in.read(raw.data(), raw.size(), "indices");
  in.finish();
  mesh.indices.resize(size_t(nt) * 3);
  for (size_t i = 0; i < mesh.indices.size(); ++i) {
    mesh.indices[i] = readLE<uint32_t>(&raw[4 * i]);
    if (mesh.indices[i] >= nv)
      throw SceneError(shapeWhere, 0, "triangle " + std::to_string(i / 3) + " refers to vertex " +
                                          std::to_string(mesh.indices[i]) + " of " + std::to_string(nv));
  }
  // Normals must be usable: a zero normal is a corrupt record (normalised here as Mitsuba does).
  for (Vec3& n : mesh.normals) {
    const float l = length(n);
    if (!(l > 0)) throw SceneError(shapeWhere, 0, "zero-length vertex normal");
    n = n / l;
  }
  if (faceNormalsHint) *faceNormalsHint = (flags & kFaceNormals) != 0;
  return mesh;
}

}  // namespace mlt
