// Scene parameters (Mitsuba's -D name=value) travel with the job: the coordinator validates and loads
// the scene with them, every worker builds its scene with them (scenes are cached per parameter set),
// and `mltfarm render --define` runs through the local farm with the same pixels as --in-process.
#include <gtest/gtest.h>

#include <cstring>

#include "common/io/exr_io.h"
#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

// A triangle light facing the camera, nothing else: a pt pixel is r times the fraction of its samples
// that hit the triangle, so the image is linear in the parameter r (exactly: the sums are integers * r).
const char* kScene = R"(<scene version="3.0.0">
  <default name="r" value="1"/>
  <sensor type="perspective">
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
  </sensor>
  <shape type="$shape"><string name="filename" value="meshes/tri.obj"/>
    <emitter type="area"><rgb name="radiance" value="$r, $r, $r"/></emitter></shape>
</scene>
)";
const char* kObj = "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n";

wire::SubmittedSettings ptWith(std::map<std::string, std::string> defines) {
  wire::SubmittedSettings s = tinySettings("pt");
  s.defines = std::move(defines);
  return s;
}

void expectScaled(const std::string& exr, const std::string& refExr, float factor) {
  const ExrImage a = readExr(exr), ref = readExr(refExr);
  ASSERT_EQ(a.rgb.size(), ref.rgb.size());
  double lit = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    ASSERT_EQ(a.rgb[i].g, factor * ref.rgb[i].g) << "pixel " << i;
    lit += ref.rgb[i].g;
  }
  EXPECT_GT(lit, 1.0);
}

TEST(FarmDefines, DefinesReachTheCoordinatorAndTheWorkers) {
  Farm farm;
  farm.startCoordinator();
  farm.startWorker(2);  // one worker renders both parameter sets: its scene cache must tell them apart
  auto c = farm.client();
  const std::vector<BundleFile> bundle{{"scene.xml", kScene}, {"meshes/tri.obj", kObj}};
  JobStatus one = c.submitBundle(bundle, "scene.xml", ptWith({{"shape", "obj"}}));
  JobStatus four = c.submitBundle(bundle, "scene.xml", ptWith({{"shape", "obj"}, {"r", "4"}}));
  ASSERT_EQ(farm.waitDone(one.jobId).state, JobState::Done);
  ASSERT_EQ(farm.waitDone(four.jobId).state, JobState::Done);
  c.fetch(one.jobId, farm.dir / "one.exr");
  c.fetch(four.jobId, farm.dir / "four.exr");
  expectScaled(farm.dir / "four.exr", farm.dir / "one.exr", 4.f);

  // Without the define the scene does not load ($shape is undefined): the loader's message.
  try {
    c.submitBundle(bundle, "scene.xml", ptWith({}));
    ADD_FAILURE() << "a scene with an undefined parameter was accepted";
  } catch (const RpcError& e) {
    EXPECT_EQ(e.code(), grpc::INVALID_ARGUMENT);
    EXPECT_NE(e.message().find("undefined parameter $shape"), std::string::npos) << e.message();
  }
  // Malformed names are refused on the wire.
  try {
    c.submitBundle(bundle, "scene.xml", ptWith({{"shape", "obj"}, {"bad name", "1"}}));
    ADD_FAILURE() << "a define with a space in its name was accepted";
  } catch (const RpcError& e) {
    EXPECT_EQ(e.code(), grpc::INVALID_ARGUMENT);
    EXPECT_NE(e.message().find("settings.defines"), std::string::npos) << e.message();
  }
}

TEST(FarmDefines, RenderWithDefineRunsOnTheLocalFarmLikeInProcess) {
  TempDir dir;
  fs::create_directories(dir / "meshes");
  std::ofstream(dir / "scene.xml") << kScene;
  std::ofstream(dir / "meshes/tri.obj") << kObj;
  auto render = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> argv{toolsDir() + "/mltfarm", "render", dir / "scene.xml", "-o", dir / (name + ".exr"),
                                  "-m", "pt", "--spp", "8", "--width", "32", "--height", "32", "-D", "shape=obj"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    ChildProcess p(argv, dir / (name + ".log"), false);
    EXPECT_EQ(p.wait(std::chrono::seconds(120)), 0) << readFile(dir / (name + ".log"));
  };
  render("farm4", {"-D", "r=4", "--workers", "2", "--threads", "1"});
  render("local4", {"-D", "r=4", "--in-process", "-q"});
  render("local1", {"--in-process", "-q"});
  EXPECT_NE(readFile(dir / "farm4.log").find("local farm"), std::string::npos) << "did not use the farm";
  const ExrImage farm = readExr(dir / "farm4.exr"), local = readExr(dir / "local4.exr");
  ASSERT_EQ(farm.rgb.size(), local.rgb.size());
  EXPECT_EQ(std::memcmp(farm.rgb.data(), local.rgb.data(), farm.rgb.size() * sizeof(Color)), 0);
  expectScaled(dir / "local4.exr", dir / "local1.exr", 4.f);
}

}  // namespace
}  // namespace mlt::farm::test
