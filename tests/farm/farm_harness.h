// Shared helpers of the farm tests: real coordinator and worker processes on loopback (ephemeral
// ports), a temporary directory per test, byte comparison of files.
#pragma once
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/farm/scene_loading.h"
#include "common/core/durable_file.h"
#include "common/job/job_types.h"
#include "coordinator/client.h"
#include "coordinator/process.h"

namespace mlt::farm::test {

namespace fs = std::filesystem;

inline std::string toolsDir() { return MLTFARM_TOOLS_DIR; }
inline std::string cornellBox() { return std::string(MLTFARM_SOURCE_DIR) + "/scenes/cornell-box.xml"; }

// A toy method's plan (tests that register a method): `units` work units of one sample per pixel each,
// unit i taking sample i.
inline JobPlan sampleUnitsPlan(const RenderSettings& settings, uint32_t units) {
  JobPlan p;
  p.settings = settings;
  for (uint32_t i = 0; i < units; ++i) {
    WorkUnit u;
    u.index = i;
    u.sampleBegin = i;
    u.sampleEnd = i + 1;
    p.units.push_back(u);
  }
  return p;
}

inline std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline size_t countOccurrences(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

// A fresh directory under the system temp dir, removed at the end unless the test failed.
struct TempDir {
  std::string path;
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "mltfarm-test-XXXXXX").string();
    path = mkdtemp(tmpl.data());
  }
  ~TempDir() {
    if (!::testing::Test::HasFailure()) fs::remove_all(path);
    else std::fprintf(stderr, "farm test: logs kept in %s\n", path.c_str());
  }
  std::string operator/(const std::string& name) const { return path + "/" + name; }
};

struct Farm {
  TempDir dir;
  std::string stateDir = dir / "state";
  std::unique_ptr<CoordinatorProcess> coordinator;
  std::vector<std::unique_ptr<ChildProcess>> workers;
  std::string token;
  int restarts = 0;

  void startCoordinator(std::vector<std::string> extra = {}, const std::string& listen = "") {
    std::vector<std::string> args{"--state-dir", stateDir, "--heartbeat", "0.2", "--lease-timeout", "1.5"};
    if (!token.empty()) args.insert(args.end(), {"--token-file", tokenFile()});
    args.insert(args.end(), extra.begin(), extra.end());
    const std::string log = dir / ("coordinator-" + std::to_string(restarts++) + ".log");
    if (listen.empty()) {
      coordinator = std::make_unique<CoordinatorProcess>(startCoordinatorProcess(toolsDir() + "/mltfarm-coordinator", args, log));
    } else {  // a fixed address (restart on the same port)
      std::vector<std::string> argv{toolsDir() + "/mltfarm-coordinator", "--listen", listen};
      argv.insert(argv.end(), args.begin(), args.end());
      auto c = std::make_unique<CoordinatorProcess>();
      c->process = ChildProcess(argv, log, true);
      auto line = c->process.readLine(std::chrono::seconds(30));
      ASSERT_TRUE(line && line->rfind("listening on ", 0) == 0) << "coordinator did not restart, see " << log;
      c->address = line->substr(13);
      coordinator = std::move(c);
    }
  }
  ChildProcess& startWorker(int threads = 1, std::vector<std::string> extra = {}) {
    std::vector<std::string> argv{toolsDir() + "/mltfarm-worker", "--coordinator", coordinator->address, "--threads",
                                  std::to_string(threads), "--cache-dir", dir / "cache"};
    if (!token.empty()) argv.insert(argv.end(), {"--token-file", tokenFile()});
    argv.insert(argv.end(), extra.begin(), extra.end());
    workers.push_back(std::make_unique<ChildProcess>(argv, dir / ("worker-" + std::to_string(workers.size()) + ".log"), false));
    return *workers.back();
  }
  // The token as the processes read it (never on argv).
  std::string tokenFile() const {
    const std::string path = dir / "token";
    writeFileDurably(path, token, 0600);
    return path;
  }
  FarmClient client(const std::string& tok = "\x01") const {
    return FarmClient({coordinator->address, tok == "\x01" ? token : tok, ""});
  }
  // Waits until `pred(status)` or the job is terminal; returns the last status.
  template <class Pred>
  JobStatus waitFor(const std::string& jobId, Pred pred, std::chrono::seconds timeout = std::chrono::seconds(120)) {
    auto c = client();
    const auto end = std::chrono::steady_clock::now() + timeout;
    JobStatus s;
    while (std::chrono::steady_clock::now() < end) {
      try {
        s = c.get(jobId);
        if (pred(s) || isTerminal(s.state)) return s;
      } catch (const RpcError&) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ADD_FAILURE() << "timed out waiting for " << jobId << ": " << describeStatus(s);
    return s;
  }
  JobStatus waitDone(const std::string& jobId) {
    return waitFor(jobId, [](const JobStatus&) { return false; });
  }
  ~Farm() {
    for (auto& w : workers) w->terminate(std::chrono::seconds(10));
    if (coordinator) coordinator->process.terminate(std::chrono::seconds(10));
  }
};

// Expects `f` to throw RpcError with `code` and a message containing `needle`.
template <class F>
void expectRpcError(F&& f, grpc::StatusCode code, const std::string& needle, const std::string& what) {
  try {
    f();
    ADD_FAILURE() << what << ": no error";
  } catch (const RpcError& e) {
    EXPECT_EQ(e.code(), code) << what << ": " << e.what();
    EXPECT_NE(e.message().find(needle), std::string::npos) << what << ": message '" << e.message() << "' lacks '"
                                                           << needle << "'";
  }
}

// `mltfarm-coordinator` started with `flags` exits 1 and its log says `message`.
inline void expectCoordinatorRefuses(const std::vector<std::string>& flags, const std::string& message) {
  TempDir dir;
  std::vector<std::string> argv{toolsDir() + "/mltfarm-coordinator", "--listen", "127.0.0.1:0", "--state-dir", dir / "state"};
  argv.insert(argv.end(), flags.begin(), flags.end());
  ChildProcess p(argv, dir / "coordinator.log", true);
  EXPECT_EQ(p.wait(std::chrono::seconds(30)), 1);
  EXPECT_NE(readFile(dir / "coordinator.log").find(message), std::string::npos) << readFile(dir / "coordinator.log");
}

// The first `units` work units of a job, planned, run and merged in this process as the farm does them.
struct LocalUnits {
  JobPlan plan;
  PartialResult merged;
};
inline LocalUnits runUnitsLocally(const std::string& sceneFile, const wire::SubmittedSettings& s, int units) {
  SceneDesc desc = loadSceneDesc(sceneFile);
  RenderSettings rs = s.settings;
  resolveSettings(rs, s.hasSize, s.hasMaxDepth, s.hasRrDepth, s.hasSpp, desc);
  auto scene = buildRenderScene(desc, rs.width, rs.height);
  LocalUnits out{planJob(*scene, rs), {}};
  for (int u = 0; u < units && u < int(out.plan.units.size()); ++u)
    out.merged.add(runWorkUnit(*scene, out.plan, out.plan.units[u]));
  return out;
}

// Small, fast settings: 32x32, few mutations, fixed seed.
inline wire::SubmittedSettings tinySettings(const std::string& method) {
  wire::SubmittedSettings s;
  s.settings.method = method;
  s.settings.seed = 7;
  s.settings.width = s.settings.height = 32;
  s.hasSize = true;
  s.settings.spp = 8;
  s.hasSpp = true;
  s.settings.samplesPerUnit = 1;
  s.settings.mutationsPerPixel = 8;
  s.settings.chains = 24;
  s.settings.bootstrapSamples = 4000;
  s.settings.integrator.maxDepth = 4;
  s.hasMaxDepth = true;
  return s;
}

}  // namespace mlt::farm::test
