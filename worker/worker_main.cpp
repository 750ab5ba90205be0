// mltfarm-worker: leases work from a coordinator and runs it on this machine's threads.
//   mltfarm-worker --coordinator HOST:PORT [--threads T] [--token-file F] [--tls-ca CA.pem [--tls-cert C --tls-key K]]
//                  [--cache-dir DIR] [--cache-max-mb MB] [--plan-cache-max-mb MB] [--spool-dir DIR] [--spool-max-mb MB] [--metrics-listen HOST:PORT]
// The token comes from --token-file or $MLTFARM_TOKEN, never from argv.
// SIGTERM/SIGINT: stop leasing, return unfinished leases (or finish them with --drain), exit 0.
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>

#include "common/farm/metrics_endpoint.h"
#include "common/farm/process_memory.h"
#include "worker/worker.h"

namespace {
mlt::farm::Worker* gWorker = nullptr;
void onSignal(int) {
  if (gWorker) gWorker->stop();  // sets an atomic flag: async-signal-safe
}
}  // namespace

int main(int argc, char** argv) {
  mlt::farm::keepFreedMemoryForReuse();  // films come and go per task (process_memory.h)
  CLI::App app{"mltfarm worker: runs leased chains / sample batches for a coordinator"};
  mlt::farm::WorkerOptions opt;
  std::string logLevel = "info";
  app.add_option("--coordinator", opt.coordinator.address, "coordinator address HOST:PORT")->required();
  app.add_option("--threads", opt.threads, "tasks run in parallel (default: all cores)")->check(CLI::Range(0, 4096));
  std::string tokenFile, argvToken;
  app.add_option("--token-file", tokenFile, "file holding the shared token (default: $MLTFARM_TOKEN, else none)");
  app.add_option("--token", argvToken, "removed: use --token-file or MLTFARM_TOKEN")->group("");  // hidden
  app.add_option("--tls-ca", opt.coordinator.tlsCa, "PEM root certificate of the coordinator (enables TLS)");
  app.add_option("--tls-cert", opt.coordinator.tlsCert, "PEM client certificate chain (mutual TLS)");
  app.add_option("--tls-key", opt.coordinator.tlsKey, "PEM private key of the client certificate");
  app.add_option("--tls-server-name", opt.coordinator.tlsServerName,
                 "name the coordinator's certificate carries, when not the host of --coordinator");
  app.add_option("--cache-dir", opt.cacheDir, "scene cache directory");
  // Cache bounds in MiB, fractions allowed; there is no "unbounded": 0 or less is refused.
  const CLI::Validator positiveMb(
      [](std::string& v) -> std::string {
        try {
          if (std::stod(v) > 0) return "";
        } catch (const std::exception&) {
        }
        return "must be a number of MiB greater than 0 (there is no unbounded cache), got '" + v.substr(0, 32) + "'";
      },
      "MB>0");
  double cacheMb = double(opt.cacheMaxBytes >> 20), planCacheMb = double(opt.planCacheMaxBytes >> 20);
  app.add_option("--cache-max-mb", cacheMb,
                 "at most this many MiB of scene bundles on disk plus built scenes in memory; least recently used "
                 "scenes no running task uses are evicted past it (> 0; 0 is refused: no unbounded cache)")
      ->check(positiveMb)->capture_default_str();
  app.add_option("--plan-cache-max-mb", planCacheMb,
                 "at most this many MiB of job plans in memory, evicted like scenes (> 0)")
      ->check(positiveMb)->capture_default_str();
  app.add_option("--spool-dir", opt.spoolDir,
                 "finished films wait here while the coordinator is away (default: CACHE_DIR/spool)");
  double spoolMb = double(opt.spoolMaxBytes >> 20);
  app.add_option("--spool-max-mb", spoolMb, "at most this many MiB of films in the spool (0: no spool)")
      ->check(CLI::Range(0.0, 1024.0 * 1024.0))->capture_default_str();
  app.add_flag("--drain", opt.drain, "on SIGTERM finish the tasks in hand instead of returning them");
  app.add_option("--debug-task-delay-ms", opt.taskDelayMs, "tests: hold each lease this long before running it")
      ->group("");  // hidden
  app.add_option("--debug-fail-unit", opt.failUnit, "tests: a task holding this work unit fails (throws)")
      ->group("");  // hidden
  std::string metricsListen;
  app.add_option("--metrics-listen", metricsListen,
                 "serve Prometheus metrics on HOST:PORT/metrics (off by default; port 0 = ephemeral, logged)");
  app.add_option("--log-level", logLevel, "trace|debug|info|warn|error")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  opt.spoolMaxBytes = uint64_t(spoolMb * 1048576.0);
  opt.cacheMaxBytes = std::max<uint64_t>(1, uint64_t(cacheMb * 1048576.0));
  opt.planCacheMaxBytes = std::max<uint64_t>(1, uint64_t(planCacheMb * 1048576.0));
  spdlog::set_default_logger(spdlog::stderr_color_mt("mltfarm"));  // stdout is for results
  spdlog::set_level(spdlog::level::from_str(logLevel));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ worker %v");
  try {
    if (!argvToken.empty()) throw std::runtime_error(mlt::farm::tokenOnCommandLineError());
    opt.coordinator.token = mlt::farm::loadToken(tokenFile);
    mlt::farm::Worker worker(opt);
    mlt::farm::MetricsEndpoint metrics;
    if (!metricsListen.empty()) {
      metrics = mlt::farm::startMetricsEndpoint(metricsListen, {worker.metrics().registry});
      spdlog::info("event=metrics_listening address={}:{}", metricsListen.substr(0, metricsListen.rfind(':')),
                   metrics.port);
    }
    gWorker = &worker;
    std::signal(SIGTERM, onSignal);
    std::signal(SIGINT, onSignal);
    int rc = worker.run();
    gWorker = nullptr;
    return rc;
  } catch (const std::exception& e) {
    spdlog::error("event=fatal error=\"{}\"", e.what());
    return 1;
  }
}
