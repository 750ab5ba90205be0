// A farm inside the test process: a coordinator serving gRPC on loopback (ephemeral port) and N workers
// on threads, each a farm::Worker as mltfarm-worker runs it. Submits a job as `mltfarm render` does
// (the CLI's settings), waits for it and fetches the EXR. Also the same settings rendered in process
// (`mltfarm render --in-process`), to compare the two.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "coordinator/client.h"
#include "coordinator/coordinator.h"
#include "coordinator/service.h"
#include "tools/cli/render_local.h"
#include "tools/cli/settings_options.h"
#include "worker/worker.h"

namespace mlt::farm::test {

// The settings as the shared CLI parser makes them from `args` (e.g. "--method rjmlt --width 16").
inline cli::CommandLineSettings parseRenderSettings(const std::string& args) {
  CLI::App app;
  cli::RenderSettingsOptions& options = cli::addRenderSettingsOptions(app);
  app.parse(args, false);
  return options.settings();
}

// `mltfarm render --in-process -q` with these settings (every core).
inline cli::LocalRenderResult renderInProcess(const std::string& scene, const cli::CommandLineSettings& cl) {
  cli::LocalRenderOptions lo;
  lo.scenePath = scene;
  lo.settings = cl.settings;
  if (cl.hasMaxDepth) lo.maxDepth = cl.settings.integrator.maxDepth;
  if (cl.hasRrDepth) lo.rrDepth = cl.settings.integrator.rrDepth;
  lo.sppGiven = cl.hasSpp;
  lo.showProgress = false;
  return cli::renderLocal(lo);
}

class InProcessFarm {
 public:
  // workerOptions: applied to every worker (coordinator address and cache directory are set here).
  // coordinatorOptions: the state directory and lease wait are set here.
  explicit InProcessFarm(int workers, WorkerOptions workerOptions = {}, CoordinatorOptions co = {}) {
    dir_ = std::filesystem::temp_directory_path() / ("mltfarm-inproc-" + std::to_string(::getpid()) + "-" +
                                                     std::to_string(serial()++));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    co.stateDir = (dir_ / "state").string();
    co.leaseWaitSeconds = 0.2;
    coordinator_ = std::make_unique<Coordinator>(co);
    ServerOptions so;
    so.listen = "127.0.0.1:0";
    server_ = startServer(so, *coordinator_, *coordinator_);
    channel_.address = "127.0.0.1:" + std::to_string(server_.port);
    for (int i = 0; i < workers; ++i) {
      WorkerOptions wo = workerOptions;
      wo.coordinator = channel_;
      wo.cacheDir = (dir_ / ("cache-" + std::to_string(i))).string();
      workers_.push_back(std::make_unique<Worker>(wo));
    }
    for (auto& w : workers_) threads_.emplace_back([&w] { w->run(); });
  }
  ~InProcessFarm() {
    stop();
    if (!::testing::Test::HasFailure()) std::filesystem::remove_all(dir_);
  }
  // Stops the workers (joined), the coordinator and the server; idempotent.
  void stop() {
    for (auto& w : workers_) w->stop();
    for (std::thread& t : threads_)
      if (t.joinable()) t.join();
    if (coordinator_ && !stopped_) {
      coordinator_->stop();
      server_.server->Shutdown();
      stopped_ = true;
    }
  }
  Worker& worker(size_t i) { return *workers_.at(i); }
  const ChannelOptions& channel() const { return channel_; }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string stateDir() const { return (dir_ / "state").string(); }

  // Submits `scene` with these settings, waits until the job ends (expects Done) and fetches its EXR to
  // `name` in the farm's directory; returns the path.
  std::string render(const std::string& scene, const cli::CommandLineSettings& cl, const std::string& name) {
    FarmClient client(channel_);
    const JobStatus submitted = client.submit(scene, cli::submittedSettings(cl));
    const JobStatus done = client.watch(submitted.jobId, [](const JobStatus&) {}, std::chrono::seconds(300));
    EXPECT_EQ(done.state, JobState::Done) << describeStatus(done);
    const std::string exr = path(name);
    client.fetch(submitted.jobId, exr);
    return exr;
  }

 private:
  static int& serial() {
    static int n = 0;
    return n;
  }
  std::filesystem::path dir_;
  std::unique_ptr<Coordinator> coordinator_;
  RunningServer server_;
  ChannelOptions channel_;
  std::vector<std::unique_ptr<Worker>> workers_;
  std::vector<std::thread> threads_;
  bool stopped_ = false;
};

}  // namespace mlt::farm::test
