// Mitsuba `serialized` shapes: the test writes files byte by byte from the format description (the
// layout comment in common/scene/serialized_reader.cpp; Mitsuba's serialized.cpp), compresses each record
// with zlib, and loads them through the XML front end.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "tests/support/temp_dir.h"
#include "common/scene/mesh_readers.h"
#include "common/scene/mitsuba_loader.h"

namespace fs = std::filesystem;

namespace mlt {
namespace {

// Little-endian byte writer.
struct Bytes {
  std::string s;
  template <typename T>
  void put(T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));  // the test host is little-endian (x86-64 / aarch64 LE)
    s.append(reinterpret_cast<const char*>(b), sizeof(T));
  }
};

struct TestShape {
  std::string name;
  bool dbl = false;
  std::vector<Vec3> p, n;
  std::vector<Vec2> uv;
  std::vector<Color> colors;
  std::vector<uint32_t> idx;
  bool faceNormalsFlag = false;
};

std::string compress(const std::string& raw) {
  uLongf size = compressBound(uLong(raw.size()));
  std::string out(size, '\0');
  EXPECT_EQ(::compress2(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
                        uLong(raw.size()), 9),
            Z_OK);
  out.resize(size);
  return out;
}

std::string serializedFile(const std::vector<TestShape>& shapes, uint16_t version) {
  Bytes file;
  std::vector<uint64_t> offsets;
  for (const TestShape& sh : shapes) {
    offsets.push_back(file.s.size());
    file.put<uint16_t>(0x041C);
    file.put<uint16_t>(version);
    Bytes rec;
    uint32_t flags = sh.dbl ? 0x2000 : 0x1000;
    if (!sh.n.empty()) flags |= 0x0001;
    if (!sh.uv.empty()) flags |= 0x0002;
    if (!sh.colors.empty()) flags |= 0x0008;
    if (sh.faceNormalsFlag) flags |= 0x0010;
    rec.put<uint32_t>(flags);
    if (version == 4) {
      rec.s += sh.name;
      rec.s.push_back('\0');
    }
    rec.put<uint64_t>(sh.p.size());
    rec.put<uint64_t>(sh.idx.size() / 3);
    auto real = [&](float v) { sh.dbl ? rec.put<double>(v) : rec.put<float>(v); };
    for (const Vec3& v : sh.p) real(v.x), real(v.y), real(v.z);
    for (const Vec3& v : sh.n) real(v.x), real(v.y), real(v.z);
    for (const Vec2& v : sh.uv) real(v.x), real(v.y);
    for (const Color& c : sh.colors) real(c.r), real(c.g), real(c.b);
    for (uint32_t i : sh.idx) rec.put<uint32_t>(i);
    file.s += compress(rec.s);
  }
  for (uint64_t o : offsets) version == 4 ? file.put<uint64_t>(o) : file.put<uint32_t>(uint32_t(o));
  file.put<uint32_t>(uint32_t(shapes.size()));
  return file.s;
}

// A unit quad in z = 0 with normals +z and uvs; and a single double-precision triangle with colours.
TestShape quad() {
  TestShape q;
  q.name = "quad";
  q.p = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  q.n = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  q.uv = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  q.idx = {0, 1, 2, 0, 2, 3};
  return q;
}
TestShape triangle() {
  TestShape t;
  t.name = "tri";
  t.dbl = true;
  t.p = {{0, 0, 2}, {2, 0, 2}, {0, 2, 2}};
  t.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  t.idx = {0, 1, 2};
  return t;
}

std::string shapeXml(const std::string& file, int index, const std::string& extra = "") {
  return "  <shape type=\"serialized\"><string name=\"filename\" value=\"" + file +
         "\"/><integer name=\"shape_index\" value=\"" + std::to_string(index) + "\"/>" + extra + "</shape>\n";
}

SceneDesc loadShapes(const TempDir& d, const std::string& shapes) {
  return loadMitsubaScene(d.write("scene.xml", "<scene version=\"3.0.0\">\n" + shapes + "</scene>\n"));
}

void expectVec(const Vec3& a, const Vec3& b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

Vec3 triNormal(const MeshDesc& m, size_t t) {
  const Vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]], c = m.positions[m.indices[3 * t + 2]];
  return normalize(cross(b - a, c - a));
}

TEST(SerializedMesh, Version4ShapesNormalsUvsIndexTransformAndFlip) {
  TempDir d;
  d.write("m.serialized", serializedFile({quad(), triangle()}, 4));
  const SceneDesc s = loadShapes(
      d, shapeXml("m.serialized", 0) +
             shapeXml("m.serialized", 1) +
             shapeXml("m.serialized", 0,
                      "<transform name=\"to_world\"><scale value=\"2\"/><translate x=\"1\" y=\"0\" z=\"3\"/></transform>"
                      "<boolean name=\"flip_normals\" value=\"true\"/>") +
             shapeXml("m.serialized", 0, "<boolean name=\"face_normals\" value=\"true\"/>"));
  ASSERT_EQ(s.meshes.size(), 4u);
  const MeshDesc& q = s.meshes[0];
  ASSERT_EQ(q.positions.size(), 4u);
  ASSERT_EQ(q.indices.size(), 6u);
  expectVec(q.positions[2], {1, 1, 0});
  ASSERT_EQ(q.normals.size(), 4u);
  for (const Vec3& n : q.normals) expectVec(n, {0, 0, 1});
  ASSERT_EQ(q.uvs.size(), 4u);
  EXPECT_FLOAT_EQ(q.uvs[1].x, 1.0f);
  EXPECT_FLOAT_EQ(q.uvs[3].y, 1.0f);  // serialized uvs are taken as stored (no flip)
  EXPECT_NE(q.name.find("m.serialized#0"), std::string::npos) << q.name;

  // Shape 1: double precision, colours dropped, no normals in the file -> smooth normals computed.
  const MeshDesc& t = s.meshes[1];
  ASSERT_EQ(t.positions.size(), 3u);
  expectVec(t.positions[1], {2, 0, 2});
  EXPECT_TRUE(t.uvs.empty());
  ASSERT_EQ(t.normals.size(), 3u);
  expectVec(t.normals[0], {0, 0, 1});

  // to_world: scale 2 then translate (1, 0, 3); flip_normals reverses winding and normals.
  const MeshDesc& f = s.meshes[2];
  expectVec(f.positions[2], {3, 2, 3});
  for (const Vec3& n : f.normals) expectVec(n, {0, 0, -1});
  for (size_t i = 0; i < 2; ++i) expectVec(triNormal(f, i), {0, 0, -1});

  EXPECT_TRUE(s.meshes[3].normals.empty());  // face_normals drops the file's vertex normals
  EXPECT_EQ(s.referencedFiles.size(), 1u);   // one file, recorded once
}

TEST(SerializedMesh, Version3AndTheFaceNormalsFlag) {
  TempDir d;
  TestShape q = quad();
  TestShape flat = quad();
  flat.faceNormalsFlag = true;
  d.write("v3.serialized", serializedFile({q, flat}, 3));
  const SceneDesc s = loadShapes(d, shapeXml("v3.serialized", 1) + shapeXml("v3.serialized", 0));
  ASSERT_EQ(s.meshes.size(), 2u);
  EXPECT_TRUE(s.meshes[0].normals.empty());  // the record's face-normals flag
  EXPECT_EQ(s.meshes[1].normals.size(), 4u);
  EXPECT_EQ(s.meshes[1].uvs.size(), 4u);
}

// Each bad file must give a SceneError naming scene.xml and the shape's line, the mesh file and the
// shape index, plus `what`.
void expectLoadError(const TempDir& d, const std::string& file, int index, const std::string& what) {
  try {
    loadShapes(d, shapeXml(file, index));
    ADD_FAILURE() << "no error for " << file << " shape " << index;
  } catch (const SceneError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("scene.xml:2:"), std::string::npos) << msg;
    EXPECT_NE(msg.find(file), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
}

TEST(SerializedMesh, TruncatedAndCorruptFilesAreErrorsNamingFileAndShape) {
  TempDir d;
  const std::string good = serializedFile({quad(), triangle()}, 4);
  d.write("good.serialized", good);
  expectLoadError(d, "good.serialized", 2, "shape_index 2 is out of range");

  // Cut the file short: the dictionary at the end is gone.
  d.write("short.serialized", good.substr(0, good.size() / 2));
  expectLoadError(d, "short.serialized", 0, "short.serialized");

  // Keep the dictionary but cut the first record's compressed stream: offsets of shape 1 now point
  // into shape 0's bytes or past them.
  {
    const TestShape q = quad();
    std::string f = serializedFile({q}, 4);
    const size_t dict = 8 + 4;
    std::string body = f.substr(0, f.size() - dict);
    std::string tail = f.substr(f.size() - dict);
    body.resize(body.size() - 20);  // drop the end of the zlib stream
    d.write("cut.serialized", body + tail);
    expectLoadError(d, "cut.serialized", 0, "shape_index 0");
    expectLoadError(d, "cut.serialized", 0, "truncated");
  }
  // Corrupt the compressed bytes of shape 1.
  {
    std::string f = good;
    const size_t dict = 2 * 8 + 4;
    uint64_t off1;
    std::memcpy(&off1, &f[f.size() - dict + 8], 8);
    for (size_t i = off1 + 6; i < off1 + 16; ++i) f[i] = char(f[i] ^ 0x5A);
    d.write("corrupt.serialized", f);
    expectLoadError(d, "corrupt.serialized", 1, "shape_index 1");
    // Shape 0 is untouched and still loads.
    EXPECT_EQ(loadShapes(d, shapeXml("corrupt.serialized", 0)).meshes.size(), 1u);
  }
  // Bad header, unknown version, absurd counts, an index out of range.
  {
    std::string f = good;
    f[0] = 0x1D;
    d.write("header.serialized", f);
    expectLoadError(d, "header.serialized", 0, "bad header");
    f = good;
    f[2] = 9;
    d.write("version.serialized", f);
    expectLoadError(d, "version.serialized", 0, "version 9");
    TestShape q = quad();
    q.idx[4] = 7;
    d.write("index.serialized", serializedFile({q}, 4));
    expectLoadError(d, "index.serialized", 0, "refers to vertex 7");
  }
  {
    // A record claiming 2^31 vertices in a few bytes.
    Bytes rec;
    rec.put<uint32_t>(0x1000);
    rec.s.push_back('\0');
    rec.put<uint64_t>(uint64_t(1) << 31);
    rec.put<uint64_t>(1);
    Bytes f;
    f.put<uint16_t>(0x041C);
    f.put<uint16_t>(4);
    f.s += compress(rec.s);
    f.put<uint64_t>(0);
    f.put<uint32_t>(1);
    d.write("huge.serialized", f.s);
    expectLoadError(d, "huge.serialized", 0, "cannot fit");
  }
  // Random byte flips anywhere never crash: they load or give a SceneError.
  for (int trial = 0; trial < 200; ++trial) {
    std::string f = good;
    const size_t pos = (size_t(trial) * 7919u) % f.size();
    f[pos] = char(f[pos] ^ (1 + trial % 255));
    d.write("fuzz.serialized", f);
    for (int index : {0, 1}) {
      try {
        loadShapes(d, shapeXml("fuzz.serialized", index));
      } catch (const SceneError&) {
      }
    }
  }
}

}  // namespace
}  // namespace mlt
