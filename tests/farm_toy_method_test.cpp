// A method is an addition, not an edit across the tree (common/methods/method.h): this file defines a toy
// method, registers it at run time, and renders it through the in-process renderer (what `mltfarm render
// --in-process` runs) and through a farm (coordinator and worker in this process, over gRPC on loopback),
// without any other file knowing about it. Its image is known exactly, so both paths are checked against
// the value, and against each other bit for bit.
//
// The toy: every work unit adds, to every pixel, one sample of value level * (unit index + 1); with U
// units the developed pixel is level * (U + 1) / 2. Its own parameter --toy-level travels by name
// (RenderSettings::params) through the CLI parser, the wire and the plan.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <thread>

#include "common/io/exr_io.h"
#include "common/methods/registry.h"
#include "coordinator/client.h"
#include "coordinator/coordinator.h"
#include "coordinator/service.h"
#include "tests/farm/farm_harness.h"
#include "tools/cli/render_local.h"
#include "tools/cli/settings_options.h"
#include "worker/worker.h"

namespace mlt {
namespace {

constexpr int kToyUnits = 5;

class ToyMethod final : public RenderMethod {
 public:
  std::string name() const override { return "toy"; }
  std::string description() const override { return "a constant image (tests only)"; }
  MethodFamily family() const override { return MethodFamily::Samples; }
  std::vector<ParamSpec> params() const override {
    ParamSpec level;
    level.name = "toy-level";
    level.defaultValue = "0.5";
    level.help = "the image's scale";
    level.min = 0;
    level.max = 100;
    return {level};
  }
  JobPlan plan(const RenderScene&, const RenderSettings& settings) const override {
    return farm::test::sampleUnitsPlan(settings, kToyUnits);
  }
  PartialResult runUnit(const RenderScene&, const JobPlan& plan, const WorkUnit& unit) const override {
    PartialResult r;
    r.film = Film(plan.settings.width, plan.settings.height);
    const double v = param(plan.settings, "toy-level") * double(unit.index + 1);
    for (int y = 0; y < plan.settings.height; ++y)
      for (int x = 0; x < plan.settings.width; ++x) r.film.addSample(Vec2(x + 0.5f, y + 0.5f), Color(v, v, v));
    r.samples = r.film.pixelCount();
    r.units = {unit.index};
    return r;
  }
  std::vector<Color> develop(const JobPlan&, const PartialResult& merged) const override {
    return merged.film.develop(0.0);
  }
  void addMetadata(const JobPlan&, const PartialResult& merged, ImageMetadata& m) const override {
    m.numbers["toyUnits"] = double(merged.units.size());
  }
};

void registerToyOnce() {
  static const bool done = [] {
    registerMethod(std::make_unique<ToyMethod>());
    return true;
  }();
  (void)done;
}

// The settings as the shared CLI parser makes them from `--method toy --toy-level 2 --width 16 --height 8`.
cli::CommandLineSettings parseToyCommandLine() {
  CLI::App app;
  cli::RenderSettingsOptions& options = cli::addRenderSettingsOptions(app);
  app.parse("--method toy --toy-level 2 --width 16 --height 8", false);
  return options.settings();
}

TEST(ToyMethod, RendersThroughTheCommandLineParserAndTheInProcessRenderer) {
  registerToyOnce();
  const cli::CommandLineSettings cl = parseToyCommandLine();
  ASSERT_EQ(cl.settings.method, "toy");
  ASSERT_EQ(cl.settings.params.at("toy-level"), "2");
  cli::LocalRenderOptions lo;
  lo.scenePath = farm::test::cornellBox();
  lo.settings = cl.settings;
  lo.showProgress = false;
  const cli::LocalRenderResult r = cli::renderLocal(lo);
  ASSERT_EQ(r.image.size(), size_t(16 * 8));
  const float expected = 2.0f * (kToyUnits + 1) / 2;  // mean of level * (i + 1), i = 0..U-1
  for (const Color& c : r.image) ASSERT_FLOAT_EQ(c.r, expected);
  EXPECT_EQ(r.metadata.strings.at("method"), "toy");
  EXPECT_EQ(r.metadata.numbers.at("toyUnits"), double(kToyUnits));

  // A parameter of another method, or a bad value, is refused naming it.
  CLI::App app;
  cli::RenderSettingsOptions& options = cli::addRenderSettingsOptions(app);
  app.parse("--method toy --toy-level=-1", false);
  try {
    options.settings();
    ADD_FAILURE() << "--toy-level -1 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("toy-level"), std::string::npos) << e.what();
  }
  CLI::App app2;
  cli::RenderSettingsOptions& options2 = cli::addRenderSettingsOptions(app2);
  app2.parse("--method pt --toy-level 1", false);
  EXPECT_THROW(options2.settings(), std::invalid_argument);
}

TEST(ToyMethod, RendersThroughTheFarmToTheSameBytes) {
  registerToyOnce();
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("mltfarm-toy-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);

  farm::CoordinatorOptions co;
  co.stateDir = (dir / "state").string();
  co.leaseWaitSeconds = 0.2;
  farm::Coordinator coordinator(co);
  farm::ServerOptions so;
  so.listen = "127.0.0.1:0";
  farm::RunningServer server = farm::startServer(so, coordinator, coordinator);
  const farm::ChannelOptions channel{"127.0.0.1:" + std::to_string(server.port), "", ""};

  farm::WorkerOptions wo;
  wo.coordinator = channel;
  wo.threads = 2;
  wo.cacheDir = (dir / "cache").string();
  farm::Worker worker(wo);
  std::thread workerThread([&] { worker.run(); });
  struct Stop {  // whatever happens below, the worker thread is stopped and joined
    farm::Worker& w;
    std::thread& t;
    ~Stop() {
      w.stop();
      if (t.joinable()) t.join();
    }
  } stopWorker{worker, workerThread};

  const cli::CommandLineSettings cl = parseToyCommandLine();
  farm::FarmClient client(channel);
  const farm::JobStatus submitted = client.submit(farm::test::cornellBox(), cli::submittedSettings(cl));
  const farm::JobStatus done = client.watch(submitted.jobId, [](const farm::JobStatus&) {}, std::chrono::seconds(120));
  EXPECT_EQ(done.state, farm::JobState::Done) << farm::describeStatus(done);
  const std::string exr = (dir / "toy.exr").string();
  client.fetch(submitted.jobId, exr);
  worker.stop();
  workerThread.join();
  coordinator.stop();
  server.server->Shutdown();

  const ExrImage farmImage = readExr(exr);
  cli::LocalRenderOptions lo;
  lo.scenePath = farm::test::cornellBox();
  lo.settings = cl.settings;
  lo.showProgress = false;
  const cli::LocalRenderResult local = cli::renderLocal(lo);
  ASSERT_EQ(farmImage.rgb.size(), local.image.size());
  for (size_t i = 0; i < local.image.size(); ++i) {
    ASSERT_EQ(farmImage.rgb[i].r, local.image[i].r) << i;
    ASSERT_EQ(farmImage.rgb[i].b, local.image[i].b) << i;
  }
  EXPECT_EQ(farmImage.metadata.numbers.at("toyUnits"), double(kToyUnits));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace mlt
