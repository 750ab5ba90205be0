// The structure drawn from the includes ("what must show" of the shared farm layer): every `#include "..."`
// of common/, proto/, coordinator/, worker/ and tools/ is read from the sources and checked against the
// layering the project declares:
//   - common/ includes nothing above it: no proto/, coordinator/, worker/, tools/, tests/, no generated
//     *.pb.h, no gRPC, protobuf or SQLite header;
//   - inside common/, a folder includes only from its own layer or lower ones, in the order of
//     MLTFARM_COMMON_LAYERS (common/CMakeLists.txt); a folder missing from that list is an error;
//   - proto/ builds on common/ only; worker/ never includes coordinator/ and coordinator/ never worker/;
//   - the graph of folders (common's layers, proto, coordinator, worker, tools) has no cycle.
// The upward includes known today are listed in kKnownUpward (each by file and target), nothing else.
// And the worker binary links no SQLite and none of the coordinator's library (its dynamic section and
// its symbols are read). The checker is first run on a small synthetic tree with known violations, so a
// checker that finds nothing cannot pass for a clean tree.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace mlt {
namespace {

namespace fs = std::filesystem;

struct Include {
  std::string file;    // root-relative path of the including file
  int line = 0;
  std::string target;  // the quoted or bracketed path
  bool quoted = true;
};

std::vector<Include> scanIncludes(const fs::path& root, const std::vector<std::string>& dirs) {
  static const std::regex re(R"(^\s*#\s*include\s*([<"])([^">]+)[">])");
  std::vector<Include> out;
  for (const std::string& d : dirs) {
    if (!fs::is_directory(root / d)) continue;
    for (const auto& e : fs::recursive_directory_iterator(root / d)) {
      const std::string ext = e.path().extension().string();
      if (!e.is_regular_file() || (ext != ".h" && ext != ".cpp" && ext != ".cc" && ext != ".hpp")) continue;
      std::ifstream in(e.path());
      std::string text;
      int n = 0;
      while (std::getline(in, text)) {
        ++n;
        std::smatch m;
        if (std::regex_search(text, m, re))
          out.push_back({fs::relative(e.path(), root).generic_string(), n, m[2].str(), m[1].str() == "\""});
      }
    }
  }
  return out;
}

std::string topDir(const std::string& path) { return path.substr(0, path.find('/')); }
bool startsWith(const std::string& s, const std::string& p) { return s.rfind(p, 0) == 0; }

// "core,sampler scene ..." -> folder -> layer index.
std::map<std::string, int> parseLayers(const std::string& spec) {
  std::map<std::string, int> layer;
  std::istringstream in(spec);
  std::string group;
  for (int i = 0; in >> group; ++i) {
    std::istringstream g(group);
    std::string folder;
    while (std::getline(g, folder, ',')) layer[folder] = i;
  }
  return layer;
}

// Node of the folder graph: "common:<layer>" for common/ (folders of one layer are one node), else the
// top-level directory.
std::string node(const std::string& path, const std::map<std::string, int>& layers) {
  const std::string top = topDir(path);
  if (top != "common") return top;
  const std::string rest = path.substr(7);
  const std::string folder = rest.substr(0, rest.find('/'));
  auto it = layers.find(folder);
  return it == layers.end() ? "common/" + folder : "common:" + std::to_string(it->second);
}

// Upward includes that are known and tolerated, one by one so that any other one fails. None today: the
// settings moved below every layer (common/settings/), the methods above the job layer.
const std::set<std::string> kKnownUpward = {};

std::vector<std::string> structureViolations(const fs::path& root, const std::string& layerSpec,
                                             const std::set<std::string>& allowed = {}) {
  const std::map<std::string, int> layers = parseLayers(layerSpec);
  std::vector<std::string> v;
  std::map<std::string, std::set<std::string>> graph;
  const std::set<std::string> projectDirs{"common", "proto", "coordinator", "worker", "tools", "tests"};
  for (const Include& inc : scanIncludes(root, {"common", "proto", "coordinator", "worker", "tools"})) {
    const std::string where = inc.file + ":" + std::to_string(inc.line) + ": #include " + inc.target + ": ";
    const std::string from = topDir(inc.file), to = topDir(inc.target);
    if (!inc.quoted) {
      if (from == "common" && (startsWith(inc.target, "grpc") || startsWith(inc.target, "google/protobuf") ||
                               startsWith(inc.target, "sqlite3")))
        v.push_back(where + "common/ uses no gRPC, protobuf or SQLite");
      continue;
    }
    if (!projectDirs.count(to)) continue;  // a library's header in quotes
    if (allowed.count(inc.file + " -> " + inc.target)) continue;
    if (from == "common") {
      if (to != "common" || inc.target.ends_with(".pb.h")) {
        v.push_back(where + "common/ includes nothing above it (proto, coordinator, worker, tools, tests)");
        continue;
      }
      const std::string f = inc.file.substr(7, inc.file.find('/', 7) - 7);
      const std::string g = inc.target.substr(7, inc.target.find('/', 7) - 7);
      if (!layers.count(f)) v.push_back(where + "folder common/" + f + " is not in MLTFARM_COMMON_LAYERS");
      else if (!layers.count(g)) v.push_back(where + "folder common/" + g + " is not in MLTFARM_COMMON_LAYERS");
      else if (layers.at(g) > layers.at(f))
        v.push_back(where + "common/" + f + " includes upward, from common/" + g + " (a higher layer)");
    }
    if (from == "proto" && to != "common" && to != "proto") v.push_back(where + "proto/ builds on common/ only");
    if (from == "worker" && to == "coordinator") v.push_back(where + "worker/ never includes coordinator/");
    if (from == "coordinator" && to == "worker") v.push_back(where + "coordinator/ never includes worker/");
    if (to == "tests" || (to == "tools" && from != "tools")) v.push_back(where + "only tests include tests/, only tools/ tools/");
    const std::string a = node(inc.file, layers), b = node(inc.target, layers);
    if (a != b) graph[a].insert(b);
  }
  // Cycles in the folder graph (depth-first search; a back edge closes a cycle).
  std::map<std::string, int> color;  // 0 unseen, 1 on the stack, 2 done
  std::vector<std::string> stack;
  std::function<void(const std::string&)> visit = [&](const std::string& n) {
    color[n] = 1;
    stack.push_back(n);
    for (const std::string& m : graph[n]) {
      if (color[m] == 1) {
        std::string cycle;
        for (auto it = std::find(stack.begin(), stack.end(), m); it != stack.end(); ++it) cycle += *it + " -> ";
        v.push_back("include cycle: " + cycle + m);
      } else if (color[m] == 0) {
        visit(m);
      }
    }
    stack.pop_back();
    color[n] = 2;
  };
  std::vector<std::string> nodes;
  for (const auto& [n, edges] : graph) nodes.push_back(n);
  for (const std::string& n : nodes)
    if (color[n] == 0) visit(n);
  return v;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += "  " + x + "\n";
  return s;
}

bool anyContains(const std::vector<std::string>& v, const std::string& what) {
  return std::any_of(v.begin(), v.end(), [&](const std::string& s) { return s.find(what) != std::string::npos; });
}

void writeFile(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

// The checker finds each kind of violation in a tree made to hold them, and nothing in a clean one.
TEST(Structure, CheckerFindsPlantedViolations) {
  const fs::path root = fs::temp_directory_path() / ("mltfarm-structure-" + std::to_string(::getpid()));
  fs::remove_all(root);
  const std::string layers = "core,sampler render farm";
  writeFile(root / "common/core/a.h", "#include <vector>\n#include \"common/sampler/s.h\"\n");
  writeFile(root / "common/sampler/s.h", "#include \"common/core/a.h\"\n");
  writeFile(root / "common/farm/f.h", "#include \"common/render/r.h\"\n#include \"proto/channel.h\"\n");
  writeFile(root / "common/render/r.h", "#include \"common/farm/f.h\"\n");
  writeFile(root / "common/farm/g.cpp", "#include \"proto/mltfarm.pb.h\"\n#include <grpcpp/grpcpp.h>\n");
  writeFile(root / "common/extra/x.h", "#include \"common/core/a.h\"\n");
  writeFile(root / "proto/channel.h", "#include \"common/farm/f.h\"\n");
  writeFile(root / "worker/w.cpp", "#include \"proto/channel.h\"\n#include \"coordinator/job_store.h\"\n");
  writeFile(root / "coordinator/job_store.h", "#include \"worker/w.h\"\n");
  const std::vector<std::string> v = structureViolations(root, layers);
  fs::remove_all(root);
  EXPECT_TRUE(anyContains(v, "common/render/r.h:1: #include common/farm/f.h: common/render includes upward")) << joined(v);
  EXPECT_TRUE(anyContains(v, "common/farm/f.h:2: #include proto/channel.h: common/ includes nothing above")) << joined(v);
  EXPECT_TRUE(anyContains(v, "common/farm/g.cpp:1: #include proto/mltfarm.pb.h")) << joined(v);
  EXPECT_TRUE(anyContains(v, "common/farm/g.cpp:2: #include grpcpp/grpcpp.h: common/ uses no gRPC")) << joined(v);
  EXPECT_TRUE(anyContains(v, "common/extra is not in MLTFARM_COMMON_LAYERS")) << joined(v);
  EXPECT_TRUE(anyContains(v, "worker/w.cpp:2: #include coordinator/job_store.h: worker/ never includes coordinator/"))
      << joined(v);
  EXPECT_TRUE(anyContains(v, "coordinator/ never includes worker/")) << joined(v);
  EXPECT_TRUE(anyContains(v, "include cycle: ")) << joined(v);
  // core and sampler share a layer: including each other is allowed.
  for (const std::string& x : v) EXPECT_FALSE(startsWith(x, "common/core/") || startsWith(x, "common/sampler/")) << x;
}

TEST(Structure, IncludesFollowTheLayers) {
  const std::vector<std::string> v = structureViolations(MLTFARM_SOURCE_DIR, MLTFARM_COMMON_LAYERS, kKnownUpward);
  EXPECT_TRUE(v.empty()) << v.size() << " violation(s):\n" << joined(v);
}

std::string run(const std::string& command) {
  std::string out;
  FILE* p = popen(command.c_str(), "r");
  if (!p) return out;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
  pclose(p);
  return out;
}

// The worker links the shared farm layer, never the coordinator's library: no libsqlite3 among its
// shared libraries, no SQLite symbol linked in statically, no job store or coordinator class.
TEST(Structure, WorkerBinaryLinksNoSqliteNorCoordinator) {
  const std::string bin = MLTFARM_WORKER_BINARY;
  ASSERT_TRUE(fs::exists(bin)) << bin;
  const std::string dynamic = run("readelf -d '" + bin + "' 2>&1");
  ASSERT_NE(dynamic.find("(NEEDED)"), std::string::npos) << "readelf gave no dynamic section:\n" << dynamic;
  EXPECT_EQ(dynamic.find("sqlite"), std::string::npos) << "the worker needs a SQLite library:\n" << dynamic;
  const std::string symbols = run("nm -C '" + bin + "' 2>&1; nm -C -D '" + bin + "' 2>&1");
  ASSERT_NE(symbols.find("mlt::farm::CoordinatorClient"), std::string::npos) << "no symbols read from " << bin;
  for (const char* forbidden : {"sqlite3_", "mlt::farm::JobStore", "mlt::farm::Coordinator::"}) {
    const size_t at = symbols.find(forbidden);
    EXPECT_EQ(at, std::string::npos) << bin << " links " << forbidden << ": "
                                     << symbols.substr(symbols.rfind('\n', at) + 1, 200);
  }
}

}  // namespace
}  // namespace mlt
