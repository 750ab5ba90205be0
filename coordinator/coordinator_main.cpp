// mltfarm-coordinator: the farm's coordinator process.
//   mltfarm-coordinator --listen 127.0.0.1:50051 --state-dir DIR [--token-file F] [--tls-cert C --tls-key K
//                       [--tls-client-ca CA]] [--insecure]
// The token comes from --token-file or $MLTFARM_TOKEN, never from argv. A non-loopback --listen needs a
// token or client certificates, or --insecure.
// Prints "listening on HOST:PORT" on stdout once serving (scripts and tests read the port from it when
// --listen ends in :0). SIGINT/SIGTERM shut down gracefully; everything accepted is already on disk.
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <semaphore>

#include "coordinator/auth.h"
#include "coordinator/coordinator.h"
#include "coordinator/crash_point.h"
#include "coordinator/service.h"
#include "proto/channel.h"

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
  std::string tokenFile, argvToken;
  app.add_option("--token-file", tokenFile,
                 "file holding the shared token every call must carry (default: $MLTFARM_TOKEN, else none)");
  app.add_option("--token", argvToken, "removed: use --token-file or MLTFARM_TOKEN")->group("");  // hidden
  app.add_option("--tls-cert", server.tlsCert, "PEM certificate chain (enables TLS)");
  app.add_option("--tls-key", server.tlsKey, "PEM private key");
  app.add_option("--tls-client-ca", server.tlsClientCa,
                 "PEM CA certificate: every client must present a certificate it signed (mutual TLS)");
  app.add_flag("--insecure", server.insecure,
               "listen on a non-loopback address with neither a token nor client certificates");
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
  std::string crashAt;
  app.add_option("--debug-crash-at", crashAt, "tests: SIGKILL itself at a named point (coordinator/crash_point.h)")
      ->group("");  // hidden
  app.add_option("--log-level", logLevel, "trace|debug|info|warn|error")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  spdlog::set_default_logger(spdlog::stderr_color_mt("mltfarm"));  // stdout is for results
  spdlog::set_level(spdlog::level::from_str(logLevel));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ coordinator %v");

  try {
    if (!argvToken.empty()) throw std::runtime_error(mlt::farm::tokenOnCommandLineError());
    server.token = mlt::farm::loadToken(tokenFile);
    mlt::farm::checkListenPolicy(server);  // before the state directory is touched
    if (!crashAt.empty()) mlt::farm::armCrashPoint(crashAt);
    mlt::farm::Coordinator coordinator(opt);
    mlt::farm::RunningServer rs = mlt::farm::startServer(server, coordinator, coordinator);
    std::string host = server.listen.substr(0, server.listen.rfind(':'));
    std::printf("listening on %s:%d\n", host.c_str(), rs.port);
    std::fflush(stdout);
    spdlog::info("event=listening address={}:{} state_dir={} token={} tls={}", host, rs.port, opt.stateDir,
                 server.token.empty() ? "off" : "on",
                 server.tlsCert.empty() ? "off" : server.tlsClientCa.empty() ? "server" : "mutual");
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
