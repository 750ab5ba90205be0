// mltfarm-coordinator: the farm's coordinator process.
//   mltfarm-coordinator --listen 127.0.0.1:50051 --state-dir DIR [--token-file F] [--tls-cert C --tls-key K
//                       [--tls-client-ca CA]] [--insecure]
// The token comes from --token-file or $MLTFARM_TOKEN, never from argv. A non-loopback --listen needs a
// token or client certificates, or --insecure.
// Prints "listening on HOST:PORT" on stdout once serving (scripts and tests read the port from it when
// --listen ends in :0), then "metrics on HOST:PORT" (--metrics-listen) and "http on HOST:PORT"
// (--http-listen) in that order. SIGINT/SIGTERM: health turns NOT_SERVING first (load balancers and
// Kubernetes readiness probes stop sending new work), --shutdown-grace seconds later the coordinator
// drains and stops; everything accepted is already on disk.
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <semaphore>
#include <thread>

#include "coordinator/auth.h"
#include "coordinator/coordinator.h"
#include "common/farm/metrics_endpoint.h"
#include "coordinator/http_server.h"
#include "coordinator/crash_point.h"
#include "coordinator/service.h"
#include "proto/channel.h"
#include "common/farm/process_memory.h"

namespace {
std::binary_semaphore gStop{0};
void onSignal(int) { gStop.release(); }
}  // namespace

int main(int argc, char** argv) {
  mlt::farm::keepFreedMemoryForReuse();  // films come and go per task (process_memory.h)
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
  std::string metricsListen, httpListen;
  double shutdownGrace = 0;
  app.add_option("--metrics-listen", metricsListen,
                 "serve Prometheus metrics on HOST:PORT/metrics (off by default; e.g. 127.0.0.1:9464)");
  app.add_option("--http-listen", httpListen,
                 "serve the web page and its JSON API on HOST:PORT (off by default; e.g. 127.0.0.1:8080; "
                 "the same token; a non-loopback address needs a token)");
  app.add_option("--shutdown-grace", shutdownGrace,
                 "on SIGTERM report NOT_SERVING this many seconds before draining (readiness probes notice)")
      ->check(CLI::Range(0.0, 600.0))->capture_default_str();
  std::string crashAt;
  app.add_option("--debug-crash-at", crashAt, "tests: SIGKILL itself at a named point (coordinator/crash_point.h)")
      ->group("");  // hidden
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
    if (!argvToken.empty()) throw std::runtime_error(mlt::farm::tokenOnCommandLineError());
    server.token = mlt::farm::loadToken(tokenFile);
    mlt::farm::checkListenPolicy(server);  // before the state directory is touched
    if (!crashAt.empty()) mlt::farm::armCrashPoint(crashAt);
    if (!httpListen.empty() && server.token.empty() && !mlt::farm::isLoopbackHost(httpListen))
      throw std::runtime_error(fmt::format("--http-listen {}: a non-loopback address needs a token (--token-file or MLTFARM_TOKEN)", httpListen));
    mlt::farm::Coordinator coordinator(opt);
    server.onUpload = [&coordinator](uint64_t bytes, double seconds) {
      coordinator.metrics().uploadBytes.Increment(double(bytes));
      coordinator.metrics().uploadSeconds.Observe(seconds);
    };
    mlt::farm::RunningServer rs = mlt::farm::startServer(server, coordinator, coordinator);
    std::string host = server.listen.substr(0, server.listen.rfind(':'));
    std::printf("listening on %s:%d\n", host.c_str(), rs.port);
    spdlog::info("event=listening address={}:{} state_dir={} token={} tls={}", host, rs.port, opt.stateDir,
                 server.token.empty() ? "off" : "on",
                 server.tlsCert.empty() ? "off" : server.tlsClientCa.empty() ? "server" : "mutual");
    mlt::farm::MetricsEndpoint metrics;
    if (!metricsListen.empty()) {
      metrics = mlt::farm::startMetricsEndpoint(
          metricsListen, {coordinator.metrics().registry, mlt::farm::farmCollector(coordinator)});
      const std::string mhost = metricsListen.substr(0, metricsListen.rfind(':'));
      std::printf("metrics on %s:%d\n", mhost.c_str(), metrics.port);
      spdlog::info("event=metrics_listening address={}:{}", mhost, metrics.port);
    }
    std::unique_ptr<mlt::farm::HttpServer> http;
    if (!httpListen.empty()) {
      http = std::make_unique<mlt::farm::HttpServer>(coordinator, mlt::farm::HttpOptions{httpListen, server.token});
      const std::string hhost = httpListen.substr(0, httpListen.rfind(':'));
      std::printf("http on %s:%d\n", hhost.c_str(), http->port());
      spdlog::info("event=http_listening address={}:{}", hhost, http->port());
    }
    std::fflush(stdout);
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    gStop.acquire();
    // Not serving first: readiness probes and load balancers stop sending new clients and workers while
    // the calls in flight finish; then drain.
    rs.server->GetHealthCheckService()->SetServingStatus(false);
    spdlog::info("event=not_serving grace_seconds={}", shutdownGrace);
    if (shutdownGrace > 0) std::this_thread::sleep_for(std::chrono::duration<double>(shutdownGrace));
    spdlog::info("event=shutdown");
    if (http) http->stop();
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
