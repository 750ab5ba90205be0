// Child processes for the local farm, the farm tests and the benchmark: fork/exec with stdout optionally
// captured (the coordinator prints "listening on HOST:PORT") and stderr appended to a log file.
// The destructor kills (SIGKILL) and reaps a child that is still running; a child is also killed when the
// thread that started it dies (PR_SET_PDEATHSIG), so a crashed test or `mltfarm render` leaves no orphans.
#pragma once
#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace mlt::farm {

class ChildProcess {
 public:
  ChildProcess() = default;
  // argv[0] is the executable path. Throws std::runtime_error if it cannot be started.
  ChildProcess(const std::vector<std::string>& argv, const std::string& logFile, bool captureStdout);
  ~ChildProcess();
  ChildProcess(ChildProcess&& o) noexcept;
  ChildProcess& operator=(ChildProcess&& o) noexcept;

  pid_t pid() const { return pid_; }
  bool running();
  // Next stdout line (without '\n'); nullopt at EOF or timeout.
  std::optional<std::string> readLine(std::chrono::milliseconds timeout);
  void signal(int sig);
  // Waits up to `timeout` for exit; returns the exit code (128 + signal if killed), nullopt on timeout.
  std::optional<int> wait(std::chrono::milliseconds timeout);
  // SIGTERM, wait up to `grace`, then SIGKILL. Returns the exit code.
  int terminate(std::chrono::milliseconds grace = std::chrono::seconds(10));

 private:
  pid_t pid_ = -1;
  int stdoutFd_ = -1;
  std::string buffer_;
  std::optional<int> exitCode_;
};

// Starts `mltfarm-coordinator` on 127.0.0.1 with an ephemeral port and returns once it listens.
struct CoordinatorProcess {
  ChildProcess process;
  std::string address;  // 127.0.0.1:PORT
};
CoordinatorProcess startCoordinatorProcess(const std::string& binary, const std::vector<std::string>& extraArgs,
                                           const std::string& logFile,
                                           std::chrono::milliseconds timeout = std::chrono::seconds(30));

// Directory holding mltfarm-coordinator and mltfarm-worker: $MLTFARM_BIN_DIR, else the directory of this
// executable if they are there, else the build tree's tools/ directory.
std::string farmBinaryDir();

}  // namespace mlt::farm
