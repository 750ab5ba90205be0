// Scenes stay inside their bundle (issue 13): the loaders' one file rule with a confinement root
// (common/scene/scene_files.h), the coordinator's submit (uploaded bundles and submissions by path,
// in process) and the worker's scene cache. Every escape is an INVALID_ARGUMENT naming file and line,
// before anything outside the bundle is opened; no message names the coordinator's state directory.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>

#include "common/farm/bundle.h"
#include "common/farm/scene_cache.h"
#include "common/scene/scene_files.h"
#include "common/scene/scene_loader.h"
#include "coordinator/coordinator.h"
#include "tests/farm/farm_harness.h"
#include "tests/support/temp_dir.h"

namespace mlt::farm::test {
namespace {

// A 16x16 scene with one OBJ (`mesh` is the filename attribute's value, on line 5).
std::string objScene(const std::string& mesh, const std::string& extra = "") {
  return "<scene version=\"3.0.0\">\n"
         "  <sensor type=\"perspective\">\n"
         "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"16\"/></film>\n"
         "  </sensor>\n"
         "  <shape type=\"obj\"><string name=\"filename\" value=\"" + mesh + "\"/>\n"
         "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"1, 1, 1\"/></emitter></shape>\n" +
         extra + "</scene>\n";
}
const char* kObj = "v -1 -1 3\nv 1 -1 3\nv 0 1 3\nf 1 2 3\n";

// Runs `f`, expecting an exception whose message contains every needle.
template <class E, class F>
std::string expectThrows(F&& f, std::initializer_list<std::string> needles) {
  try {
    f();
  } catch (const E& e) {
    const std::string m = e.what();
    for (const std::string& n : needles) EXPECT_NE(m.find(n), std::string::npos) << "'" << m << "' lacks '" << n << "'";
    return m;
  }
  ADD_FAILURE() << "no error";
  return {};
}

TEST(SceneConfinement, TheLoaderRefusesEveryWayOutOfItsRoot) {
  mlt::TempDir dir("confine");
  const std::string outside = dir.write("secret.obj", kObj);
  const std::string root = (dir.path() / "bundle").string();
  auto load = [&](const std::string& scene, const std::map<std::string, std::string>& defines = {}) {
    return loadScene(dir.write("bundle/scene.xml", scene), defines, root);
  };
  dir.write("bundle/meshes/tri.obj", kObj);
  EXPECT_EQ(load(objScene("meshes/tri.obj")).referencedFiles.size(), 1u);                   // inside: fine
  EXPECT_EQ(load(objScene("meshes/../meshes/tri.obj")).referencedFiles.size(), 1u);         // '..' that stays inside
  expectThrows<SceneError>([&] { load(objScene(outside)); }, {"scene.xml:5:", "filename", "absolute paths"});
  expectThrows<SceneError>([&] { load(objScene("../secret.obj")); }, {"scene.xml:5:", "'../secret.obj'", "outside"});
  // A -D value that injects a path: refused where it is used.
  const std::string injected = objScene("$m", "");
  expectThrows<SceneError>([&] { load(injected, {{"m", "../secret.obj"}}); }, {"scene.xml:5:", "outside"});
  // An include of the coordinator's database, two levels up.
  dir.write("farm.db", "SQLite format 3");
  expectThrows<SceneError>([&] { load(objScene("meshes/tri.obj", "<include filename=\"../farm.db\"/>\n")); },
                           {"scene.xml:7:", "'../farm.db'", "outside"});
  // A symlink inside the root that points out of it.
  std::filesystem::create_symlink(outside, dir.path() / "bundle" / "link.obj");
  expectThrows<SceneError>([&] { load(objScene("link.obj")); }, {"scene.xml:5:", "outside"});
  // The scene file itself must be inside.
  expectThrows<SceneError>([&] { loadScene(dir.write("other.xml", objScene("secret.obj")), {}, root); }, {"outside"});
  // Without a root (local rendering) the old rule holds: files next to the scene or anywhere.
  EXPECT_EQ(loadScene(dir.write("bundle/scene.xml", objScene("../secret.obj"))).referencedFiles.size(), 1u);
}

TEST(SceneConfinement, PbrtFilesAreConfinedToo) {
  mlt::TempDir dir("confine_pbrt");
  dir.write("outside.pbrt", "WorldBegin\nWorldEnd\n");
  const std::string scene = dir.write("bundle/scene.pbrt",
                                      "Camera \"perspective\"\nFilm \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                                      "WorldBegin\nInclude \"../outside.pbrt\"\nWorldEnd\n");
  expectThrows<SceneError>([&] { loadScene(scene, {}, (dir.path() / "bundle").string()); },
                           {"scene.pbrt:4:", "'../outside.pbrt'", "outside"});
}

TEST(SceneConfinement, PathInsideRootIsTheOneCheck) {
  mlt::TempDir dir("confine_root");
  const std::string root = (dir.path() / "r").string();
  std::filesystem::create_directories(root);
  EXPECT_EQ(pathInsideRoot(root, root + "/a/b.obj").value_or("?"), "a/b.obj");
  EXPECT_FALSE(pathInsideRoot(root, root));
  EXPECT_FALSE(pathInsideRoot(root, root + "/../r2/x"));
  EXPECT_FALSE(pathInsideRoot(root, "/etc/passwd"));
  EXPECT_FALSE(pathInsideRoot(root + "/", root + "/../r/../x"));
  // The local CLI's bundle collection uses it: a file next to the scene's folder is refused by the loader.
  dir.write("r/scene.xml", objScene("../secret.obj"));
  dir.write("secret.obj", kObj);
  expectThrows<FarmError>([&] { collectBundle(root + "/scene.xml"); }, {"scene.xml:5:", "outside"});
}

// --- the coordinator, in process ------------------------------------------------------------------

struct InProcess {
  mlt::TempDir dir{"confine_coord"};
  std::unique_ptr<Coordinator> coordinator;
  explicit InProcess(const std::string& sceneRoot = "") {
    CoordinatorOptions o;
    o.stateDir = (dir.path() / "state").string();
    o.sceneRoot = sceneRoot;
    coordinator = std::make_unique<Coordinator>(o);
  }
  std::string stateDir() const { return (dir.path() / "state").string(); }
  SubmitRequest bundle(std::vector<BundleFile> files, const std::string& sceneFile = "scene.xml") const {
    SubmitRequest r;
    const wire::SubmittedSettings s = tinySettings("pt");
    r.settings = s.settings;
    r.hasSize = r.hasMaxDepth = r.hasSpp = true;
    r.settings.width = r.settings.height = 16;
    r.bundle = std::move(files);
    r.bundleSceneFile = sceneFile;
    return r;
  }
  // Expects submit to fail with `code` and the needles, and the message to keep the state dir private.
  void refuses(SubmitRequest r, FarmError::Code code, std::initializer_list<std::string> needles) {
    const std::string m = expectThrows<FarmError>(
        [&] {
          try {
            coordinator->submit(std::move(r));
          } catch (const FarmError& e) {
            EXPECT_EQ(int(e.code()), int(code)) << e.what();
            throw;
          }
        },
        needles);
    EXPECT_EQ(m.find(dir.path().string()), std::string::npos) << "message names a server path: " << m;
  }
};

TEST(SceneConfinement, SubmitRefusesScenesThatReachOutOfTheirBundle) {
  InProcess farm;
  mlt::TempDir elsewhere("confine_elsewhere");
  const std::string secret = elsewhere.write("secret.obj", kObj);
  using C = FarmError::Code;
  // Fine: the mesh is in the bundle.
  const JobStatus ok = farm.coordinator->submit(farm.bundle({{"scene.xml", objScene("m/tri.obj")}, {"m/tri.obj", kObj}}));
  EXPECT_EQ(ok.width, 16);
  farm.refuses(farm.bundle({{"scene.xml", objScene(secret)}}), C::InvalidArgument, {"scene.xml:5:", "filename", "absolute"});
  // The same file by a relative path from the coordinator's copy of the bundle (STATE/scenes/HASH/).
  const std::string up = "../../../../" + std::filesystem::path(secret).parent_path().filename().string() + "/secret.obj";
  farm.refuses(farm.bundle({{"scene.xml", objScene(up)}}), C::InvalidArgument, {"scene.xml:5:", "outside"});
  farm.refuses(farm.bundle({{"scene.xml", objScene("m/tri.obj", "<include filename=\"../../farm.db\"/>\n")}, {"m/tri.obj", kObj}}),
               C::InvalidArgument, {"scene.xml:7:", "'../../farm.db'", "outside"});
  // Another client's bundle, by its hash.
  farm.refuses(farm.bundle({{"scene.xml", objScene("../" + ok.sceneHash + "/m/tri.obj")}}), C::InvalidArgument,
               {"scene.xml:5:", "outside"});
  // A -D value that injects a path.
  SubmitRequest injected = farm.bundle({{"scene.xml", objScene("$mesh", "<default name=\"mesh\" value=\"m/tri.obj\"/>\n")},
                                        {"m/tri.obj", kObj}});
  injected.defines = {{"mesh", "../../farm.db"}};
  farm.refuses(injected, C::InvalidArgument, {"scene.xml:5:", "outside"});
  // A file missing from the bundle is named relative to the bundle.
  farm.refuses(farm.bundle({{"scene.xml", objScene("m/tri.obj")}}), C::InvalidArgument, {"scene.xml:5:", "not found (tried m/tri.obj)"});
}

TEST(SceneConfinement, SubmittingByPathNeedsASceneRootAndStaysInIt) {
  mlt::TempDir scenes("confine_scenes");
  const std::string scene = scenes.write("root/sub/scene.xml", objScene("../meshes/tri.obj"));
  scenes.write("root/meshes/tri.obj", kObj);
  scenes.write("outside.xml", objScene("root/meshes/tri.obj"));
  scenes.write("root/escape.xml", objScene("../outside.obj"));
  scenes.write("outside.obj", kObj);
  {
    InProcess off;  // no scene root: off
    SubmitRequest r = off.bundle({});
    r.coordinatorPath = scene;
    off.refuses(r, FarmError::Code::FailedPrecondition, {"coordinator_path", "--scene-root"});
  }
  InProcess on((scenes.path() / "root").string());
  SubmitRequest r = on.bundle({});
  r.coordinatorPath = "sub/scene.xml";  // relative to the root
  EXPECT_EQ(on.coordinator->submit(r).width, 16);
  r.coordinatorPath = scene;  // absolute, inside
  EXPECT_EQ(on.coordinator->submit(r).width, 16);
  r.coordinatorPath = (scenes.path() / "outside.xml").string();
  on.refuses(r, FarmError::Code::InvalidArgument, {"coordinator_path", "outside the coordinator's scene root"});
  r.coordinatorPath = "../outside.xml";
  on.refuses(r, FarmError::Code::InvalidArgument, {"coordinator_path", "outside"});
  r.coordinatorPath = "escape.xml";
  on.refuses(r, FarmError::Code::InvalidArgument, {"root/escape.xml:5:", "outside"});
}

TEST(SceneConfinement, WorkersReadOnlyTheFetchedBundleAndCheckItsHash) {
  mlt::TempDir dir("confine_worker");
  dir.write("secret.obj", kObj);
  const std::vector<BundleFile> good{{"scene.xml", objScene("tri.obj")}, {"tri.obj", kObj}};
  const std::vector<BundleFile> escaping{{"scene.xml", objScene("../../secret.obj")}};
  std::vector<BundleFile> served;
  SceneCache cache((dir.path() / "cache").string(), [&](const std::string&) { return served; });
  served = good;
  EXPECT_TRUE(cache.get(bundleHash(good), "scene.xml", {}, 16, 16));
  // A bundle that does not hash to the lease's scene hash.
  served = good;
  served[1].data += "\n";
  expectThrows<FarmError>([&] { cache.get(std::string(64, 'a'), "scene.xml", {}, 16, 16); }, {"hashes to"});
  // A bundle whose scene reaches out of the cache directory (two levels up: the secret).
  served = escaping;
  expectThrows<FarmError>([&] { cache.get(bundleHash(escaping), "scene.xml", {}, 16, 16); }, {"scene.xml:5:", "outside"});
}

}  // namespace
}  // namespace mlt::farm::test
