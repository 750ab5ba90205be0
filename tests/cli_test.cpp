// The `mltfarm` executable end to end: errors give exit code 2 and a message naming the file; a small
// render writes an EXR (with metadata) and a PNG; the image does not depend on the thread count; a Markov
// chain render prints its summary (b, acceptance, mutations/s); a time-budgeted one records the mutations
// per pixel it chose, and rendering with that value reproduces the image bit for bit.
// The executable is found next to this test's build directory (BUILD/tools/mltfarm).
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <bit>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "common/io/exr_io.h"
#include "common/job/direct_light_rule.h"
#include "common/job/mlt_job.h"
#include "common/methods/pss_method.h"

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

// env: assignments put before the command ("NAME=value "), e.g. a TMPDIR.
RunResult run(const std::string& args, const std::string& env = "") {
  const std::string cmd = env + mltfarmExe().string() + " " + args + " 2>&1";
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

// A .pbrt scene goes to the pbrt-v3 front end (by extension); its errors name file and line too.
TEST_F(Cli, RendersPbrtScenesByExtension) {
  const fs::path out = tempDir() / "checker.exr";
  const RunResult r = run("render " + kScenes + "checker-spheres.pbrt --method pt --spp 1 --width 16 --height 16 --in-process -o " + out.string());
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(fs::exists(out)) << r.output;
  const fs::path scene = tempDir() / "broken.pbrt";
  std::ofstream(scene) << "Camera \"perspective\"\nWorldBegin\nShape \"teapot_of_doom\"\n";
  const RunResult b = run("render " + scene.string() + " --spp 1 --in-process -o " + (tempDir() / "b.exr").string());
  EXPECT_EQ(b.exitCode, 2) << b.output;
  EXPECT_NE(b.output.find("broken.pbrt:3"), std::string::npos) << b.output;
}

TEST_F(Cli, UsageErrorsAreRejected) {
  EXPECT_NE(run("render " + kScenes + "cornell-box.xml --method nonsense -o /tmp/x.exr").exitCode, 0);
  EXPECT_NE(run("render " + kScenes + "cornell-box.xml --spp 0 -o /tmp/x.exr").exitCode, 0);
  EXPECT_NE(run("render " + kScenes + "cornell-box.xml --spp 1").exitCode, 0);  // no -o
  EXPECT_NE(run("render " + kScenes + "cornell-box.xml --method mmlt --kernel nonsense -o /tmp/x.exr").exitCode, 0);
  EXPECT_NE(run("render " + kScenes + "cornell-box.xml --method mmlt --splatting nonsense -o /tmp/x.exr").exitCode, 0);
  const RunResult help = run("render --help");
  EXPECT_EQ(help.exitCode, 0);
  EXPECT_NE(help.output.find("segments"), std::string::npos) << help.output;
}

// submit shares render's settings options (tools/cli/settings_options.h): a bad value is refused before
// any connection is attempted (nothing listens on port 1), with a message naming the option.
TEST_F(Cli, SubmitRefusesBadSettingsNamingTheOptionBeforeConnecting) {
  const std::string submit = "submit " + kScenes + "cornell-box.xml --coordinator 127.0.0.1:1 ";
  for (const char* bad : {"--sigma 0", "--kernel nonsense", "--splatting veach", "--spp 0", "--s1 0.1 --s2 0.05"}) {
    const RunResult r = run(submit + bad);
    EXPECT_NE(r.exitCode, 0) << bad << "\n" << r.output;
    const std::string option = std::string(bad).substr(0, std::string(bad).find(' '));
    EXPECT_NE(r.output.find(option == "--s1" ? "--s2" : option), std::string::npos) << bad << "\n" << r.output;
    EXPECT_EQ(r.output.find("127.0.0.1:1"), std::string::npos) << bad << ": tried to connect\n" << r.output;
  }
  const RunResult help = run("submit --help");
  EXPECT_EQ(help.exitCode, 0);
  for (const char* option : {"--kernel", "--s1", "--s2", "--sigma", "--splatting", "--separate-direct"})
    EXPECT_NE(help.output.find(option), std::string::npos) << option << "\n" << help.output;
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
  // --mis-heuristic reaches the renderer (other weights, other pixels) and the metadata says so; the
  // default (power) writes no entry, so a default render's bytes stay those of earlier versions.
  EXPECT_EQ(a.metadata.strings.count("misHeuristic"), 0u);
  const RunResult bal = run("render " + scene + common + "--mis-heuristic balance -o " + (dir / "bal.exr").string());
  ASSERT_EQ(bal.exitCode, 0) << bal.output;
  const ExrImage c = readExr((dir / "bal.exr").string());
  EXPECT_EQ(c.metadata.strings.at("misHeuristic"), "balance");
  ASSERT_EQ(c.rgb.size(), a.rgb.size());
  size_t differ = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) differ += a.rgb[i].g != c.rgb[i].g;
  EXPECT_GT(differ, a.rgb.size() / 4);
}

// The summary line of a sample method names it (it once passed the method's std::string to printf's %s,
// which printed bytes of the string object).
TEST_F(Cli, SampleRenderSummaryNamesTheMethodAndItsSamples) {
  const fs::path out = tempDir() / "summary_pt.exr";
  const RunResult r = run("render " + kScenes + "cornell-box.xml --method pt --spp 2 --width 16 --height 16 "
                          "--threads 1 --in-process -o " + out.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("pt: 512 samples in "), std::string::npos) << r.output;
}

// --farm-dir keeps the local farm's state and logs; a directory holding another farm's state is refused
// (its coordinator would resume the jobs there), and so is --farm-dir on a render that runs in-process.
TEST_F(Cli, FarmDirKeepsTheLocalFarmsLogsAndRefusesAUsedDirectory) {
  const fs::path dir = tempDir() / "farm-dir";
  fs::remove_all(dir);
  const fs::path out = tempDir() / "farm_dir.exr";
  const std::string job = "render " + kScenes + "cornell-box.xml --method pt --spp 1 --width 16 --height 16 --threads 1 ";
  const RunResult r = run(job + "--farm-dir " + dir.string() + " -o " + out.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(fs::exists(out));
  EXPECT_TRUE(fs::is_regular_file(dir / "coordinator.log"));
  EXPECT_TRUE(fs::is_regular_file(dir / "worker-0.log"));
  const RunResult again = run(job + "--farm-dir " + dir.string() + " -o " + out.string());
  EXPECT_NE(again.exitCode, 0);
  EXPECT_NE(again.output.find("--farm-dir " + dir.string() + ": not empty"), std::string::npos) << again.output;
  const RunResult inProcess = run(job + "--in-process --farm-dir " + (tempDir() / "unused").string() + " -o " + out.string());
  EXPECT_NE(inProcess.exitCode, 0);
  EXPECT_NE(inProcess.output.find("--farm-dir is for the local farm"), std::string::npos) << inProcess.output;
}

// A PNG that cannot be written after a local-farm render (here: --png names a directory) is an error
// naming it; the EXR is kept, and the farm's temporary state directory is removed as on success.
TEST_F(Cli, UnwritablePngAfterALocalFarmRenderKeepsTheExrAndRemovesTheFarmState) {
  const fs::path tmp = tempDir() / "png-fail-tmp";
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  const fs::path pngDir = tempDir() / "png-is-a-dir";
  fs::create_directories(pngDir);
  const fs::path out = tempDir() / "png_fail.exr";
  fs::remove(out);
  const RunResult r = run("render " + kScenes + "cornell-box.xml --method pt --spp 1 --width 16 --height 16 "
                          "--threads 1 -q --png " + pngDir.string() + " -o " + out.string(),
                          "TMPDIR=" + tmp.string() + " ");
  EXPECT_NE(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find(pngDir.string()), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_regular_file(out)) << "the fetched EXR is lost";
  EXPECT_TRUE(fs::is_empty(tmp)) << "the local farm's temporary state was left in " << tmp;
}

bool sameBits(const ExrImage& a, const ExrImage& b) {
  if (a.width != b.width || a.height != b.height || a.rgb.size() != b.rgb.size()) return false;
  for (size_t i = 0; i < a.rgb.size(); ++i)
    for (int c = 0; c < 3; ++c)
      if (std::bit_cast<uint32_t>(a.rgb[i][c]) != std::bit_cast<uint32_t>(b.rgb[i][c])) return false;
  return true;
}

const std::string kSmallMmlt = " --method mmlt --width 32 --height 32 --max-depth 4 --bootstrap 2000 --seed 5 "
                               "--threads 2 --in-process --direct-light chains ";

// Without --direct-light the plan's pilot chooses (common/job/direct_light_rule.h), and the log and the
// image say what it chose and why: on the Cornell box, a pt pass for the direct light.
TEST_F(Cli, AutomaticDirectLightSaysWhatItChose) {
  const fs::path out = tempDir() / "auto.exr";
  const RunResult r = run("render " + kScenes + "cornell-box.xml --method mmlt --width 64 --height 64 --max-depth 4 "
                          "--mutations-per-pixel 2 --seed 3 --threads 2 --in-process -o " + out.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(std::regex_search(r.output, std::regex("mmlt: direct light by a pt pass \\(--direct-light separate\\): "
                                                     "the pilot's [0-9]+ bdpt samples")))
      << r.output;
  // The summary, printed from the image's metadata (as after a farm render), says it too.
  const auto& n = readExr(out.string()).metadata.numbers;
  EXPECT_EQ(n.at("separateDirect"), 1.0);
  // Sized by the pilot's share (mlt_job.h, directSppPerMutation) at 2 mutations per pixel, and the log says so.
  DirectLightPilot pilot;
  pilot.share = n.at("directLightShare");
  RenderSettings separate;
  separate.directLight = DirectLight::Separate;
  const int spp = directSppFor(directSppPerMutation(*findChainJobSpec("mmlt"), separate, &pilot), 2);
  EXPECT_EQ(n.at("directSpp"), double(spp));
  EXPECT_NE(r.output.find(fmt::format("mmlt: the pt pass gets {} samples per pixel: ", spp)), std::string::npos) << r.output;
  EXPECT_TRUE(std::regex_search(r.output, std::regex(fmt::format("direct light \\(paths of at most 2 segments\\): a pt "
                                                                 "pass of {} samples per pixel \\(the pilot's choice: "
                                                                 "[0-9.]+% of the light", spp))))
      << r.output;
  EXPECT_GE(n.at("directLightShare"), kDirectMinShare);
  EXPECT_LE(n.at("directLightCv"), kDirectMaxCv);
}

TEST_F(Cli, MarkovChainRenderPrintsBAcceptanceAndMutationsPerSecond) {
  const fs::path out = tempDir() / "summary.exr";
  const RunResult r = run("render " + kScenes + "cornell-box.xml" + kSmallMmlt + "--mutations-per-pixel 4 -o " +
                          out.string());  // stderr is a pipe here, not a terminal
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::string number = "[0-9.e+-]+";
  EXPECT_TRUE(std::regex_search(r.output, std::regex("b = " + number + " ± " + number + " \\(rel\\. " + number +
                                                     "%, from [0-9]+ samples: [0-9]+ bootstrap candidates")))
      << r.output;
  for (int k = 1; k <= 4; ++k)  // the per-length table: k, b_k ± SE, chains, mutations, acceptance
    EXPECT_TRUE(std::regex_search(r.output, std::regex("\\n +" + std::to_string(k) + " +" + number + " ± " + number +
                                                       " +[0-9]+ +[0-9]+ +" + number + "%")))
        << "k = " << k << "\n" << r.output;
  EXPECT_TRUE(std::regex_search(r.output, std::regex("acceptance " + number + "% \\(large steps " + number +
                                                     "%, small steps " + number + "%\\)")))
      << r.output;
  EXPECT_TRUE(std::regex_search(r.output, std::regex("4096 mutations .* = " + number + " mutations/s"))) << r.output;
  const ExrImage img = readExr(out.string());
  const auto& n = img.metadata.numbers;
  // The warning about b's uncertainty appears exactly when its recorded relative standard error is above 2%.
  EXPECT_EQ(r.output.find("relative standard error of b") != std::string::npos, n.at("bStdErr") > 0.02 * n.at("b"))
      << r.output;
  // b rests on the candidates whose count no value decided (the first round; length 1 from camera rays) and
  // every large step (develop.h). The candidates cost what 2000 of the chains' mutations per length do
  // (bootstrap.h, chainMixCost): at least a quarter of that many per length, and not more than the cheapest
  // length's candidates could buy (4 lengths here; a candidate draws at least 4 numbers, a mutation of this
  // mix about 10).
  EXPECT_LE(n.at("bootstrapSamples"), 4 * 2000.0 * 4);
  EXPECT_GE(n.at("bootstrapSamples"), 4 * 500.0);
  EXPECT_EQ(n.at("bSamples"), n.at("bootstrapSamplesInB") + n.at("largeSteps"));
  EXPECT_LE(n.at("bootstrapSamplesInB"), n.at("bootstrapSamples"));
  EXPECT_EQ(n.at("bootstrapPerLength"), 2000.0);
  for (const char* key : {"b", "bStdErr", "acceptance", "acceptanceLarge", "acceptanceSmall", "b1", "bStdErr4",
                          "chains2", "mutations3", "acceptance4", "mutationsPerSecond"})
    EXPECT_TRUE(n.count(key)) << key;
  EXPECT_EQ(n.at("mutations"), 4096.0);
  EXPECT_EQ(n.at("mutations1") + n.at("mutations2") + n.at("mutations3") + n.at("mutations4"), 4096.0);
  EXPECT_GT(n.at("acceptance"), 0.0);
  EXPECT_LT(n.at("acceptance"), 1.0);
  EXPECT_GT(n.at("bStdErr"), 0.0);

  // -q: no summary (the warning about b stays).
  const RunResult quiet = run("render " + kScenes + "cornell-box.xml" + kSmallMmlt + "--mutations-per-pixel 4 -q -o " +
                              out.string());
  ASSERT_EQ(quiet.exitCode, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find("mutations/s"), std::string::npos) << quiet.output;
}

// -q silences the bootstrap's info lines too (they printed through -q before); a warning would still show.
TEST_F(Cli, QuietRenderPrintsNoSummaryAndNoLogLines) {
  const fs::path out = tempDir() / "quiet.exr";
  const RunResult loud = run("render " + kScenes + "cornell-box.xml" + kSmallMmlt + "--mutations-per-pixel 1 -o " + out.string());
  ASSERT_EQ(loud.exitCode, 0) << loud.output;
  EXPECT_NE(loud.output.find("[info] mmlt: bootstrap"), std::string::npos) << loud.output;  // the check below can fail
  // 1 mutation per pixel and a bootstrap of 256 candidates per length: b's error is above 2%, which warns.
  const RunResult quiet = run("render " + kScenes + "cornell-box.xml --method mmlt --width 32 --height 32 --max-depth 4 "
                              "--bootstrap 256 --seed 5 --threads 2 --in-process --mutations-per-pixel 1 -q -o " + out.string());
  ASSERT_EQ(quiet.exitCode, 0) << quiet.output;
  // (Warnings stay: this one's b, and with so small a bootstrap maybe a crowded start, which names it too.)
  EXPECT_EQ(quiet.output.find("[info]"), std::string::npos) << quiet.output;
  EXPECT_EQ(quiet.output.find("mutations/s"), std::string::npos) << quiet.output;
  EXPECT_NE(quiet.output.find("warning: the relative standard error of b"), std::string::npos) << quiet.output;
}

TEST_F(Cli, TimeBudgetedMarkovChainRenderIsReproducibleFromItsMutationsPerPixel) {
  const fs::path dir = tempDir();
  const std::string scene = kScenes + "cornell-box.xml";
  // No --bootstrap: the bootstrap is sized from the budget, and the printed command names its size.
  const std::string kAutoMmlt = " --method mmlt --width 32 --height 32 --max-depth 4 --seed 5 --threads 2 --in-process ";
  const RunResult timed = run("render " + scene + kAutoMmlt + "--time 0.5 -o " + (dir / "timed.exr").string());
  ASSERT_EQ(timed.exitCode, 0) << timed.output;
  const ExrImage a = readExr((dir / "timed.exr").string());
  ASSERT_TRUE(a.metadata.numbers.count("mutationsPerPixel")) << timed.output;
  const double mpp = a.metadata.numbers.at("mutationsPerPixel");
  EXPECT_GT(mpp, 0.0);
  EXPECT_EQ(a.metadata.numbers.at("workUnits"), a.metadata.numbers.at("workUnitsPlanned"));  // every chain ran
  EXPECT_EQ(a.metadata.numbers.at("mutations"), std::round(mpp * 32 * 32));
  // The printed value is the one to type: it reads back as the recorded double.
  std::smatch match;
  ASSERT_TRUE(std::regex_search(timed.output, match, std::regex("--mutations-per-pixel ([0-9.e+-]+)"))) << timed.output;
  EXPECT_EQ(std::stod(match[1].str()), mpp) << timed.output;
  std::smatch boot;
  ASSERT_TRUE(std::regex_search(timed.output, boot, std::regex("--bootstrap ([0-9]+) instead of --time"))) << timed.output;
  EXPECT_EQ(std::stod(boot[1].str()), a.metadata.numbers.at("bootstrapPerLength"));
  EXPECT_GE(a.metadata.numbers.at("bootstrapPerLength"), 4096.0);  // kMinBootstrapPerLength

  const RunResult again = run("render " + scene + kAutoMmlt + "--mutations-per-pixel " + match[1].str() +
                              " --bootstrap " + boot[1].str() + " -q -o " + (dir / "again.exr").string());
  ASSERT_EQ(again.exitCode, 0) << again.output;
  const ExrImage b = readExr((dir / "again.exr").string());
  EXPECT_EQ(b.metadata.numbers.at("mutationsPerPixel"), mpp);
  EXPECT_EQ(b.metadata.strings.at("kernel"), "kelemen");
  EXPECT_TRUE(sameBits(a, b)) << "mutations per pixel " << match[1].str();
}


// `mltfarm eval --farm`: every run is a job on the local farm (coordinator + worker processes); the
// records say so and carry the chain statistics the farm's EXR metadata brings back.
TEST_F(Cli, EvalRunsThroughTheFarm) {
  const fs::path dir = tempDir() / "eval-farm";
  const RunResult r = run("eval --scenes " + kScenes + "furnace-sphere.xml --methods pt,pssmlt --runs 2 "
                          "--equal-samples --budgets 2 --width 16 --height 16 --ref-spp 16 --bootstrap 2000 "
                          "--no-ref-cache --kernel gaussian --sigma 0.02 --farm -o " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  // The kernel options reach the farm's render: its last EXR (a pssmlt run) records them.
  const ExrImage last = readExr((dir / "farm-tmp" / "farm-run.exr").string());
  EXPECT_EQ(last.metadata.strings.at("kernel"), "gaussian");
  EXPECT_EQ(float(last.metadata.numbers.at("kernelSigma")), 0.02f);
  std::ifstream csv(dir / "runs.csv");
  std::string line;
  std::getline(csv, line);  // header
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    EXPECT_NE(line.find(",farm,"), std::string::npos) << line;
    if (line.find(",pssmlt,") != std::string::npos) {
      // scene,method,mode,budget_index,budget,run,seed,seconds,work,samples,relMSE,MSE,MAE,meanErr,acceptance,...
      std::vector<std::string> f;
      std::stringstream ss(line);
      for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
      ASSERT_GT(f.size(), 14u) << line;
      ASSERT_FALSE(f[14].empty()) << "acceptance travels back from the farm's EXR: " << line;
      EXPECT_GT(std::stod(f[14]), 0.0) << line;
      EXPECT_LE(std::stod(f[14]), 1.0) << line;
    }
  }
  EXPECT_EQ(rows, 2 * 2);
}

// `mltfarm eval`'s chain options reach every run and the reproduction command line: the runs' seeds do
// not depend on them and images are pure functions of settings and seed, so the same runs with another
// kernel (or large-step probability, or s2) have other errors, and the defaults given explicitly the same.
TEST_F(Cli, EvalChainOptionsReachTheRunsAndTheCommandLine) {
  auto evalRelMse = [](const std::string& name, const std::string& options) {
    const fs::path dir = tempDir() / ("eval-" + name);
    const RunResult r = run("eval --scenes " + kScenes + "furnace-sphere.xml --methods pssmlt --runs 1 "
                            "--equal-samples --budgets 1 --width 8 --height 8 --ref-spp 8 --bootstrap 500 "
                            "--no-maps --no-charts -q -t 1 " + options + " -o " + dir.string());
    EXPECT_EQ(r.exitCode, 0) << options << "\n" << r.output;
    std::ifstream csv(dir / "runs.csv");
    std::string line;
    std::getline(csv, line);  // header
    std::getline(csv, line);
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    EXPECT_GT(f.size(), 10u) << line;
    std::ifstream md(dir / "summary.md");
    const std::string summary((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
    return std::make_pair(f.size() > 10 ? f[10] : std::string(), summary);
  };
  const auto base = evalRelMse("default", "");
  const auto explicitDefaults = evalRelMse("explicit", "--kernel kelemen --s1 0.0009765625 --s2 0.015625 --large-step 0.3");
  const auto gaussian = evalRelMse("gaussian", "--kernel gaussian --sigma 0.2");
  const auto s2 = evalRelMse("s2", "--s2 0.25");
  const auto largeStep = evalRelMse("large-step", "--large-step 0.7");
  EXPECT_EQ(base.first, explicitDefaults.first);
  EXPECT_NE(base.first, gaussian.first);
  EXPECT_NE(base.first, s2.first);
  EXPECT_NE(base.first, largeStep.first);
  EXPECT_NE(gaussian.second.find("--kernel gaussian --sigma 0.2"), std::string::npos) << gaussian.second;
  EXPECT_NE(s2.second.find("--kernel kelemen --s1 0.0009765625 --s2 0.25"), std::string::npos) << s2.second;
  EXPECT_NE(largeStep.second.find("--large-step 0.7"), std::string::npos) << largeStep.second;
  // Validated like render's: a step outside (0, 1], s2 below s1.
  for (const char* bad : {"--sigma 0", "--s1 1.5", "--s1 0.1 --s2 0.05", "--kernel nonsense"}) {
    const RunResult r = run("eval --scenes " + kScenes + "furnace-sphere.xml --methods pssmlt -o /tmp/unused " + bad);
    EXPECT_NE(r.exitCode, 0) << bad << "\n" << r.output;
    const std::string option = std::string(bad).substr(0, std::string(bad).find(' '));
    EXPECT_NE(r.output.find(option == "--s1" && std::string(bad).find("--s2") != std::string::npos ? "--s2" : option),
              std::string::npos) << bad << "\n" << r.output;
  }
}

}  // namespace
}  // namespace mlt
