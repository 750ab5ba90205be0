// Seconds to first sample for a large mesh: load the scene (a 1M-triangle grid as a Mitsuba serialized
// mesh, or as a binary PLY), build the render scene (Embree BVH) and evaluate one pt sample. One
// iteration = the whole sequence; the mesh files are written once, outside the timing.
#include <benchmark/benchmark.h>
#include <unistd.h>
#include <zlib.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/integrators/evaluators.h"
#include "common/render/render_scene.h"
#include "common/sampler/sample_source.h"
#include "common/scene/scene_loader.h"

namespace fs = std::filesystem;

namespace mlt {
namespace {

constexpr int kGrid = 708;  // 708 x 708 quads = 1,002,528 triangles

template <typename T>
void put(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));  // little-endian host
}

const fs::path& dir() {
  static const fs::path d = [] {
    fs::path p = fs::temp_directory_path() / ("mlt_scene_load_bench_" + std::to_string(::getpid()));
    fs::create_directories(p);
    static struct Remover {
      fs::path p;
      ~Remover() {
        std::error_code ec;
        fs::remove_all(p, ec);
      }
    } remover{p};
    // Grid over [-1,1]^2 at z = 0 (a gentle bump so the BVH is not flat), uvs, no normals.
    const int n = kGrid + 1;
    std::string rec, ply;
    put<uint32_t>(rec, 0x1000 | 0x0002);
    rec.push_back('\0');
    put<uint64_t>(rec, uint64_t(n) * n);
    put<uint64_t>(rec, uint64_t(kGrid) * kGrid * 2);
    std::string pos, uv, idx;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const float x = -1 + 2.0f * i / kGrid, y = -1 + 2.0f * j / kGrid;
        put<float>(pos, x), put<float>(pos, y), put<float>(pos, 0.05f * (x * x - y * y));
        put<float>(uv, float(i) / kGrid), put<float>(uv, float(j) / kGrid);
      }
    for (int j = 0; j < kGrid; ++j)
      for (int i = 0; i < kGrid; ++i) {
        const uint32_t a = j * n + i, b = a + 1, c = a + n + 1, d = a + n;
        for (uint32_t v : {a, b, c, a, c, d}) put<uint32_t>(idx, v);
      }
    rec += pos + uv + idx;
    uLongf size = compressBound(uLong(rec.size()));
    std::string z(size, '\0');
    compress2(reinterpret_cast<Bytef*>(z.data()), &size, reinterpret_cast<const Bytef*>(rec.data()), uLong(rec.size()), 6);
    z.resize(size);
    std::string file;
    put<uint16_t>(file, 0x041C), put<uint16_t>(file, 4);
    file += z;
    put<uint64_t>(file, 0), put<uint32_t>(file, 1);
    std::ofstream(p / "grid.serialized", std::ios::binary) << file;
    // The same grid as binary PLY (vertex x y z u v; triangles as 3-index lists).
    ply = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(n * n) +
          "\nproperty float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\nelement face " +
          std::to_string(kGrid * kGrid * 2) + "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int v = 0; v < n * n; ++v) ply.append(pos, size_t(v) * 12, 12).append(uv, size_t(v) * 8, 8);
    for (size_t t = 0; t < size_t(kGrid) * kGrid * 2; ++t) ply.append(1, char(3)).append(idx, t * 12, 12);
    std::ofstream(p / "grid.ply", std::ios::binary) << ply;
    for (const char* kind : {"serialized", "ply"}) {
      std::ofstream(p / (std::string(kind) + ".xml"))
          << "<scene version=\"3.0.0\"><sensor type=\"perspective\"><transform name=\"to_world\">"
             "<lookat origin=\"0,0,3\" target=\"0,0,0\" up=\"0,1,0\"/></transform><film type=\"hdrfilm\">"
             "<integer name=\"width\" value=\"64\"/><integer name=\"height\" value=\"64\"/></film></sensor>"
             "<shape type=\"" << kind << "\"><string name=\"filename\" value=\"grid." << kind << "\"/>"
             "<bsdf type=\"diffuse\"/></shape><emitter type=\"constant\"/></scene>\n";
    }
    return p;
  }();
  return d;
}

void secondsToFirstSample(benchmark::State& state, const char* kind) {
  const std::string scenePath = (dir() / (std::string(kind) + ".xml")).string();
  IntegratorSettings is;
  is.maxDepth = 5;
  for (auto _ : state) {
    const SceneDesc desc = loadScene(scenePath);
    const auto scene = RenderScene::build(desc);
    const auto ev = makeEvaluator(*scene, "pt", is);
    IndependentSource source(1, 0);
    PathContribution out;
    const Vec2 pixel(32, 32);
    ev->evaluate(source, &pixel, out);
    benchmark::DoNotOptimize(out);
  }
  state.counters["triangles"] = double(kGrid) * kGrid * 2;
}

BENCHMARK_CAPTURE(secondsToFirstSample, serialized_1M, "serialized")->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(secondsToFirstSample, ply_1M, "ply")->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
}  // namespace mlt

BENCHMARK_MAIN();
