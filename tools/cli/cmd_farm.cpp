// Farm client subcommands: talk to a running mltfarm-coordinator.
//   mltfarm submit SCENE.xml --coordinator ADDR [render settings as for render] [--priority P] [--path] [--watch] [-o OUT.exr]
//   mltfarm status JOB --coordinator ADDR       mltfarm jobs --coordinator ADDR
//   mltfarm watch JOB --coordinator ADDR        mltfarm cancel JOB --coordinator ADDR
//   mltfarm fetch JOB -o OUT.exr [--png OUT.png] --coordinator ADDR
//   mltfarm delete JOB --coordinator ADDR       (a finished, failed or cancelled job and its files)
// --coordinator defaults to $MLTFARM_COORDINATOR, else 127.0.0.1:50051; the token comes from --token-file,
// else $MLTFARM_TOKEN (never from argv).
#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <stdexcept>

#include "coordinator/client.h"
#include "tools/cli/commands.h"
#include "tools/cli/settings_options.h"

namespace mlt::cli {
namespace {

using farm::FarmClient;
using farm::JobStatus;

struct Connection {
  farm::ChannelOptions channel;
  std::string tokenFile, argvToken;
  void add(CLI::App& sub) {
    if (const char* a = std::getenv("MLTFARM_COORDINATOR")) channel.address = a;
    else channel.address = "127.0.0.1:50051";
    sub.add_option("--coordinator", channel.address, "Coordinator address HOST:PORT")->capture_default_str();
    sub.add_option("--token-file", tokenFile, "File holding the shared token (default: $MLTFARM_TOKEN)");
    sub.add_option("--token", argvToken, "Removed: use --token-file or MLTFARM_TOKEN")->group("");  // hidden
    sub.add_option("--tls-ca", channel.tlsCa, "PEM root certificate of the coordinator (enables TLS)");
    sub.add_option("--tls-cert", channel.tlsCert, "PEM client certificate chain (mutual TLS)");
    sub.add_option("--tls-key", channel.tlsKey, "PEM private key of the client certificate");
    sub.add_option("--tls-server-name", channel.tlsServerName,
                   "Name the coordinator's certificate carries, when not the host of --coordinator");
  }
  // The channel with its token: call when the command runs (after parsing).
  const farm::ChannelOptions& resolved() {
    if (!argvToken.empty()) throw std::runtime_error(farm::tokenOnCommandLineError());
    channel.token = farm::loadToken(tokenFile);
    return channel;
  }
};

void printStatus(const JobStatus& s) { std::printf("%s\n", farm::describeStatus(s).c_str()); }

// What a watcher cares about: a line is printed only when one of these changes (not for ETA or
// elapsed-time ticks alone).
std::string watchKey(const JobStatus& s) {
  return fmt::format("{}|{}|{}|{}|{}|{}|{}|{}", int(s.state), s.phase, s.tasksDone, s.unitsDone, s.workDone, s.b,
                     s.failedAttempts, s.error);
}

int watchToEnd(FarmClient& client, const std::string& jobId) {
  std::string printed;
  JobStatus last = client.watch(jobId, [&printed](const JobStatus& s) {
    const std::string key = watchKey(s);
    if (key == printed) return;
    printed = key;
    std::fprintf(stderr, "%s\n", farm::describeStatus(s).c_str());
  });
  return last.state == farm::JobState::Done ? 0 : kExitError;
}

// --- submit -----------------------------------------------------------------------------------
// submit's own options; the render settings are the shared group (settings_options.h), the same as
// `mltfarm render` takes.
struct SubmitOptions {
  Connection conn;
  std::string scene, name, out, png;
  int priority = 0;
  bool path = false, watch = false;
};

CommandRun setupSubmit(CLI::App& sub) {
  auto o = std::make_shared<SubmitOptions>();
  o->conn.add(sub);
  sub.add_option("scene", o->scene, "Scene file: uploaded with every file it references")->required();
  const RenderSettingsOptions* settings = &addRenderSettingsOptions(sub);  // owned by `sub`
  sub.add_option("--priority", o->priority, "Higher runs first; FIFO within a priority")->capture_default_str();
  sub.add_option("--name", o->name, "Name shown in listings");
  sub.add_flag("--path", o->path, "Send the scene's path instead of its files (the coordinator must read it)");
  sub.add_flag("--watch", o->watch, "Follow progress until the job ends");
  sub.add_option("-o,--output", o->out, "With --watch: fetch the EXR here when done");
  sub.add_option("--png", o->png, "With --watch: fetch the PNG here when done");
  return [o, settings]() -> int {
    const wire::SubmittedSettings s = submittedSettings(settings->settings());
    FarmClient client(o->conn.resolved());
    JobStatus st = client.submit(o->scene, s, o->priority, o->name, o->path);
    std::printf("%s\n", st.jobId.c_str());
    std::fflush(stdout);
    if (!o->watch) return 0;
    int rc = watchToEnd(client, st.jobId);
    if (rc == 0 && !o->out.empty()) client.fetch(st.jobId, o->out, "exr");
    if (rc == 0 && !o->png.empty()) client.fetch(st.jobId, o->png, "png");
    return rc;
  };
}

// --- status / watch / cancel / jobs / fetch ---------------------------------------------------------
struct JobOptions {
  Connection conn;
  std::string job, out, png;
};

CommandSetup jobCommand(int (*body)(FarmClient&, const JobOptions&), bool needsOutput = false) {
  return [body, needsOutput](CLI::App& sub) -> CommandRun {
    auto o = std::make_shared<JobOptions>();
    o->conn.add(sub);
    sub.add_option("job", o->job, "Job id (job-N)")->required();
    if (needsOutput) {
      sub.add_option("-o,--output", o->out, "Where to write the EXR")->required();
      sub.add_option("--png", o->png, "Also fetch the PNG preview here");
    }
    return [o, body] {
      FarmClient client(o->conn.resolved());
      return body(client, *o);
    };
  };
}

const CommandRegistration kSubmit("submit", "Submit a render job to a coordinator", setupSubmit);
const CommandRegistration kStatus("status", "Show a job's state and progress",
                                  jobCommand([](FarmClient& c, const JobOptions& o) {
                                    printStatus(c.get(o.job));
                                    return 0;
                                  }));
const CommandRegistration kWatch("watch", "Follow a job's progress until it ends",
                                 jobCommand([](FarmClient& c, const JobOptions& o) { return watchToEnd(c, o.job); }));
const CommandRegistration kCancel("cancel", "Cancel a job", jobCommand([](FarmClient& c, const JobOptions& o) {
                                    printStatus(c.cancel(o.job));
                                    return 0;
                                  }));
const CommandRegistration kDelete("delete", "Delete a finished, failed or cancelled job and its files",
                                  jobCommand([](FarmClient& c, const JobOptions& o) {
                                    c.remove(o.job);
                                    std::printf("%s deleted\n", o.job.c_str());
                                    return 0;
                                  }));
const CommandRegistration kFetch("fetch", "Download a finished job's image",
                                 jobCommand(
                                     [](FarmClient& c, const JobOptions& o) {
                                       uint64_t n = c.fetch(o.job, o.out, "exr");
                                       std::printf("%s: %llu bytes\n", o.out.c_str(), (unsigned long long)n);
                                       if (!o.png.empty()) c.fetch(o.job, o.png, "png");
                                       return 0;
                                     },
                                     true));
const CommandRegistration kJobs("jobs", "List a coordinator's jobs", [](CLI::App& sub) -> CommandRun {
  auto conn = std::make_shared<Connection>();
  conn->add(sub);
  return [conn] {
    FarmClient client(conn->resolved());
    for (const JobStatus& s : client.list()) printStatus(s);
    return 0;
  };
});

}  // namespace
}  // namespace mlt::cli
