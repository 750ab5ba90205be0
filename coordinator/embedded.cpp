// The local farm (see embedded.h).
#include "coordinator/embedded.h"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <exception>
#include <filesystem>
#include <fmt/format.h>
#include <random>
#include <thread>

#include "common/core/durable_file.h"
#include "coordinator/client.h"
#include "coordinator/process.h"

namespace fs = std::filesystem;

namespace mlt::farm {

EmbeddedFarmResult runEmbeddedFarm(const EmbeddedFarmOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  EmbeddedFarmResult result;
  bool tempState = o.stateDir.empty();
  if (tempState) {
    std::string tmpl = (fs::temp_directory_path() / "mltfarm-local-XXXXXX").string();
    if (!mkdtemp(tmpl.data())) throw std::runtime_error("cannot create a temporary state directory");
    result.stateDir = tmpl;
  } else {
    result.stateDir = o.stateDir;
    fs::create_directories(o.stateDir);
  }
  const std::string bin = farmBinaryDir();
  std::random_device rd;
  const std::string token = fmt::format("{:08x}{:08x}{:08x}{:08x}", rd(), rd(), rd(), rd());
  const std::string tokenFile = result.stateDir + "/token";  // never on argv: ps shows argv to everyone
  writeFileDurably(tokenFile, token, 0600);
  const int W = o.workers > 0 ? o.workers : int(std::max(1u, std::thread::hardware_concurrency()));

  CoordinatorProcess coord = startCoordinatorProcess(
      bin + "/mltfarm-coordinator",
      {"--state-dir", result.stateDir, "--token-file", tokenFile, "--heartbeat", "0.5", "--lease-timeout", "10",
       "--scene-root", fs::absolute(o.scenePath).parent_path().string()},
      result.stateDir + "/coordinator.log");
  std::vector<ChildProcess> workers;
  for (int i = 0; i < W; ++i)
    workers.emplace_back(std::vector<std::string>{bin + "/mltfarm-worker", "--coordinator", coord.address, "--threads",
                                                  std::to_string(o.threadsPerWorker), "--token-file", tokenFile, "--cache-dir",
                                                  result.stateDir + "/worker-cache"},
                         fmt::format("{}/worker-{}.log", result.stateDir, i), false);
  result.startupSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  bool signalled = false;
  auto stop = [&] {  // the job is done: SIGTERM to the coordinator also ends the workers' long polls at once
    if (signalled) return;
    signalled = true;
    for (auto& w : workers) w.signal(SIGTERM);
    coord.process.signal(SIGTERM);
  };
  auto shutdown = [&] {
    stop();
    for (auto& w : workers) w.terminate(std::chrono::seconds(10));
    coord.process.terminate(std::chrono::seconds(10));
  };
  try {
    FarmClient client({coord.address, token, ""});
    const auto submitted = std::chrono::steady_clock::now();
    JobStatus st = client.submit(o.scenePath, o.settings, 0, fs::path(o.scenePath).filename().string(), true);
    st = client.watch(st.jobId, o.onStatus);
    if (st.state != JobState::Done)
      throw std::runtime_error(fmt::format("local farm: job {} ended {}: {} (logs in {})", st.jobId,
                                           jobStateName(st.state), st.error, result.stateDir));
    if (!o.outExr.empty()) client.fetch(st.jobId, o.outExr, "exr");
    if (!o.outPng.empty()) client.fetch(st.jobId, o.outPng, "png");
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - submitted).count();
    result.status = st;
    stop();
  } catch (const RpcError& e) {
    shutdown();
    throw std::runtime_error(e.message());  // the coordinator's message (e.g. the scene loader's)
  } catch (...) {
    shutdown();
    throw;
  }
  // The caller's step after the fetch (the PNG) runs while the farm exits; its failure (a file the caller
  // writes, the EXR already saved) is the caller's error: the farm's temporary state goes all the same.
  std::exception_ptr afterFetchError;
  if (o.afterFetch) {
    try {
      o.afterFetch();
    } catch (...) {
      afterFetchError = std::current_exception();
    }
  }
  shutdown();
  if (tempState && !o.keepLogs) fs::remove_all(result.stateDir);
  if (afterFetchError) std::rethrow_exception(afterFetchError);
  return result;
}

}  // namespace mlt::farm
