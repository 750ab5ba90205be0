// `mltfarm submit` takes the render settings `mltfarm render` takes (tools/cli/settings_options.h), and
// they reach the coordinator: the kernel, splatting and separate-direct options typed on submit's command
// line are in the job's plan (read back from the coordinator's partial EXRs) and in the image's
// metadata, and the farm's image is bit-identical to `render --in-process` given the same arguments.
#include <gtest/gtest.h>

#include <cstring>

#include "common/io/exr_io.h"
#include "coordinator/merge.h"
#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

// Small and fast (32x32, 8 mutations per pixel); non-default kernel and splatting, bdpt for direct light.
const std::vector<std::string> kSettings{
    "-m", "mmlt", "--kernel", "gaussian", "--sigma", "0.02", "--splatting", "expected-value", "--separate-direct",
    "--seed", "7", "--width", "32", "--height", "32", "--max-depth", "4", "--spp", "4", "--mutations-per-pixel", "8",
    "--chains", "16", "--bootstrap", "4000"};

int runCli(std::vector<std::string> argv, const std::string& log) {
  argv.insert(argv.begin(), toolsDir() + "/mltfarm");
  ChildProcess p(argv, log, false);
  const std::optional<int> rc = p.wait(std::chrono::seconds(300));
  return rc ? *rc : -1;
}

TEST(FarmSubmitSettings, KernelSplattingAndSeparateDirectReachThePlanAndMatchRender) {
  Farm farm;
  farm.startCoordinator({"--keep-partials"});
  farm.startWorker(2);
  const std::string farmExr = farm.dir / "submitted.exr";
  std::vector<std::string> submit{"submit", cornellBox(), "--coordinator", farm.coordinator->address, "--watch",
                                  "-o", farmExr};
  submit.insert(submit.end(), kSettings.begin(), kSettings.end());
  ASSERT_EQ(runCli(submit, farm.dir / "submit.log"), 0) << readFile(farm.dir / "submit.log");

  // The coordinator planned the job with them: every partial carries the plan.
  size_t partials = 0;
  for (const auto& e : fs::directory_iterator(farm.stateDir + "/jobs/job-1/partials")) {
    const RenderSettings s = readPartialExr(e.path().string()).plan.settings;
    ++partials;
    EXPECT_EQ(s.method, "mmlt");
    EXPECT_EQ(s.kernel, MutationKernel::Gaussian);
    EXPECT_EQ(s.gaussianSigma, 0.02f);
    EXPECT_EQ(s.splatting, MltSplatting::ExpectedValue);  // not the default (Kelemen MIS)
    EXPECT_EQ(s.directLight, DirectLight::Separate);
  }
  EXPECT_GT(partials, 0u);
  const ExrImage submitted = readExr(farmExr);
  EXPECT_EQ(submitted.metadata.strings.at("kernel"), "gaussian");
  EXPECT_EQ(float(submitted.metadata.numbers.at("kernelSigma")), 0.02f);
  EXPECT_EQ(submitted.metadata.strings.at("splatting"), "expected-value");
  EXPECT_EQ(submitted.metadata.numbers.at("separateDirect"), 1.0);

  // The same arguments to `render`: the same settings, hence the same pixels.
  const std::string localExr = farm.dir / "rendered.exr";
  std::vector<std::string> render{"render", cornellBox(), "--in-process", "-q", "--threads", "2", "-o", localExr};
  render.insert(render.end(), kSettings.begin(), kSettings.end());
  ASSERT_EQ(runCli(render, farm.dir / "render.log"), 0) << readFile(farm.dir / "render.log");
  const ExrImage rendered = readExr(localExr);
  ASSERT_EQ(rendered.rgb.size(), submitted.rgb.size());
  EXPECT_EQ(std::memcmp(rendered.rgb.data(), submitted.rgb.data(), rendered.rgb.size() * sizeof(Color)), 0)
      << "submit and render gave different images for the same settings";
  double sum = 0;
  for (const Color& c : rendered.rgb) sum += c.r + c.g + c.b;
  EXPECT_GT(sum, 0.0);
}

}  // namespace
}  // namespace mlt::farm::test
