// mltfarm-coordinator: the farm's coordinator process.
//   mltfarm-coordinator --listen 127.0.0.1:50051 --state-dir DIR [--token T] [--tls-cert C --tls-key K]
// Prints "listening on HOST:PORT" on stdout once serving (scripts and tests read the port from it when
// --listen ends in :0). SIGINT/SIGTERM shut down gracefully; everything accepted is already on disk.
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <semaphore>

#include "coordinator/coordinator.h"
#include "coordinator/service.h"

namespace {
std::binary_semaphore gStop{0};
void onSignal(int) { gStop.release(); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"mltfarm coordinator: accepts render jobs, runs the bootstrap, leases work to workers"};
  mlt::farm::ServerOptions server;
  mlt::farm::CoordinatorOptions opt;
  std::string logLevel = "info";
  app.add_option("--listen", server.listen, "address to listen on (loopback by default; port 0 = ephemeral)")
      ->capture_default_str();
  app.add_option("--state-dir", opt.stateDir, "state directory (SQLite database, scenes, results)")->required();
  app.add_option("--token", server.token, "shared token every call must carry (default: none)");
  if (const char* t = std::getenv("MLTFARM_TOKEN"); t && server.token.empty()) server.token = t;
  app.add_option("--tls-cert", server.tlsCert, "PEM certificate chain (enables TLS)");
  app.add_option("--tls-key", server.tlsKey, "PEM private key");
  app.add_option("--lease-timeout", opt.leaseTimeoutSeconds, "seconds before an unrenewed lease is requeued")
      ->check(CLI::Range(0.2, 3600.0))->capture_default_str();
  app.add_option("--heartbeat", opt.heartbeatSeconds, "heartbeat interval told to workers (seconds)")
      ->check(CLI::Range(0.05, 600.0))->capture_default_str();
  app.add_flag("--keep-partials", opt.keepPartials, "also write each accepted task as a partial EXR");
  app.add_option("--max-attempts", opt.maxAttempts,
                 "a task that failed this many times (worker error reports and expired leases) fails its job")
      ->check(CLI::Range(1, 1000))->capture_default_str();
  app.add_option("--preview-every", opt.previewEverySeconds,
                 "write STATE/jobs/JOB/preview.exr and .png of the tasks accepted so far this often (seconds; 0 = off)")
      ->check(CLI::Range(0.0, 86400.0))->capture_default_str();
  app.add_option("--scene-root", opt.sceneRoot,
                 "let clients submit a scene by its path under this directory (off by default: clients upload "
                 "the scene's files); such a scene reads only files under it");
  app.add_option("--max-bundle-bytes", opt.quotas.maxBundleBytes, "largest scene bundle a client may upload (bytes)")
      ->check(CLI::Range(uint64_t(1), uint64_t(4) << 30))->capture_default_str();
  app.add_option("--max-bundle-files", opt.quotas.maxBundleFiles, "most files in one scene bundle")
      ->check(CLI::Range(1u, 1000000u))->capture_default_str();
  app.add_option("--max-jobs-per-client", opt.quotas.maxJobsPerClient,
                 "most unfinished jobs one client (peer host) may have")
      ->check(CLI::Range(1u, 1000000u))->capture_default_str();
  app.add_option("--max-job-name", opt.quotas.maxJobNameBytes, "longest job name (bytes)")
      ->check(CLI::Range(0u, 1u << 20))->capture_default_str();
  app.add_option("--log-level", logLevel, "trace|debug|info|warn|error")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  spdlog::set_default_logger(spdlog::stderr_color_mt("mltfarm"));  // stdout is for results
  spdlog::set_level(spdlog::level::from_str(logLevel));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ coordinator %v");

  try {
    mlt::farm::Coordinator coordinator(opt);
    mlt::farm::RunningServer rs = mlt::farm::startServer(server, coordinator, coordinator);
    std::string host = server.listen.substr(0, server.listen.rfind(':'));
    std::printf("listening on %s:%d\n", host.c_str(), rs.port);
    std::fflush(stdout);
    spdlog::info("event=listening address={}:{} state_dir={} token={} tls={}", host, rs.port, opt.stateDir,
                 server.token.empty() ? "off" : "on", server.tlsCert.empty() ? "off" : "on");
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    gStop.acquire();
    spdlog::info("event=shutdown");
    // Stop first: it wakes long polls (LeaseWork, WatchJob) so that the server's shutdown does not wait
    // for them to time out. Handlers still answer (uploads are still stored) until the server is down.
    coordinator.stop();
    rs.server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  } catch (const std::exception& e) {
    spdlog::error("event=fatal error=\"{}\"", e.what());
    return 1;
  }
  return 0;
}
