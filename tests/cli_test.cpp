// The `mltfarm` executable end to end: errors give exit code 2 and a message naming the file; a small
// render writes an EXR (with metadata) and a PNG; the image does not depend on the thread count.
// The executable is found next to this test's build directory (BUILD/tools/mltfarm).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <bit>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/io/exr_io.h"

namespace mlt {
namespace {

namespace fs = std::filesystem;

fs::path mltfarmExe() {
  const fs::path self = fs::read_symlink("/proc/self/exe");
  return self.parent_path().parent_path() / "tools" / "mltfarm";
}

struct RunResult {
  int exitCode = -1;
  std::string output;  // stdout + stderr
};

RunResult run(const std::string& args) {
  const std::string cmd = mltfarmExe().string() + " " + args + " 2>&1";
  RunResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

fs::path tempDir() {
  const fs::path dir = fs::temp_directory_path() / ("mltfarm_cli_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir;
}

const std::string kScenes = std::string(MLTFARM_SOURCE_DIR) + "/scenes/";

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(mltfarmExe())) << "build the mltfarm target first: " << mltfarmExe();
  }
};

TEST_F(Cli, MissingSceneIsAnErrorWithExitCode2) {
  const std::string out = (tempDir() / "x.exr").string();
  const RunResult r = run("render /nonexistent/scene.xml --spp 1 -o " + out);
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/scene.xml"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Cli, UnwritableOutputIsReportedBeforeRendering) {
  const RunResult r = run("render " + kScenes + "cornell-box.xml --spp 1 -o /nonexistent_dir/x.exr");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("/nonexistent_dir"), std::string::npos) << r.output;
}

TEST_F(Cli, MalformedSceneNamesFileAndLine) {
  const fs::path scene = tempDir() / "broken.xml";
  std::ofstream(scene) << "<scene version=\"3.0.0\">\n  <shape type=\"teapot_of_doom\"/>\n</scene>\n";
  const RunResult r = run("render " + scene.string() + " --spp 1 -o " + (tempDir() / "b.exr").string());
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("broken.xml:2"), std::string::npos) << r.output;
}

TEST_F(Cli, UsageErrorsAreRejected) {
  EXPECT_NE(run("render " + kScenes + "cornell-box.xml --method nonsense -o /tmp/x.exr").exitCode, 0);
  EXPECT_NE(run("render " + kScenes + "cornell-box.xml --spp 0 -o /tmp/x.exr").exitCode, 0);
  EXPECT_NE(run("render " + kScenes + "cornell-box.xml --spp 1").exitCode, 0);  // no -o
  const RunResult help = run("render --help");
  EXPECT_EQ(help.exitCode, 0);
  EXPECT_NE(help.output.find("segments"), std::string::npos) << help.output;
}

TEST_F(Cli, RenderWritesExrWithMetadataAndPngAndIsThreadCountIndependent) {
  const fs::path dir = tempDir();
  const std::string scene = kScenes + "cornell-box.xml";
  const std::string common = " --method bdpt --spp 2 --width 24 --height 16 --seed 7 --max-depth 4 -q ";
  const RunResult one = run("render " + scene + common + "--threads 1 -o " + (dir / "one.exr").string());
  ASSERT_EQ(one.exitCode, 0) << one.output;
  const RunResult two = run("render " + scene + common + "--threads 2 -o " + (dir / "two.exr").string());
  ASSERT_EQ(two.exitCode, 0) << two.output;
  EXPECT_TRUE(fs::exists(dir / "one.png"));

  const ExrImage a = readExr((dir / "one.exr").string()), b = readExr((dir / "two.exr").string());
  EXPECT_EQ(a.width, 24);
  EXPECT_EQ(a.height, 16);
  EXPECT_EQ(a.metadata.strings.at("method"), "bdpt");
  EXPECT_EQ(a.metadata.strings.at("seed"), "7");
  EXPECT_EQ(a.metadata.numbers.at("spp"), 2.0);
  EXPECT_EQ(a.metadata.numbers.at("maxDepth"), 4.0);
  EXPECT_EQ(a.metadata.strings.at("sceneHash").size(), 64u);  // hex SHA-256
  EXPECT_EQ(a.metadata.strings.at("sceneHash"), b.metadata.strings.at("sceneHash"));
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  double sum = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    for (int c = 0; c < 3; ++c) ASSERT_EQ(std::bit_cast<uint32_t>(a.rgb[i][c]), std::bit_cast<uint32_t>(b.rgb[i][c])) << i;
    sum += a.rgb[i].g;
  }
  EXPECT_GT(sum, 0.0);  // the light reaches the camera
}

}  // namespace
}  // namespace mlt
