// Child processes (see process.h).
#include "coordinator/process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <stdexcept>
#include <thread>

namespace mlt::farm {

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& logFile, bool captureStdout) {
  if (argv.empty()) throw std::runtime_error("ChildProcess: empty argv");
  int pipeFds[2] = {-1, -1};
  if (captureStdout && pipe2(pipeFds, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
  int logFd = -1;
  if (!logFile.empty()) {
    logFd = open(logFile.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (logFd < 0) throw std::runtime_error(fmt::format("{}: cannot open log: {}", logFile, std::strerror(errno)));
  }
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive the process (thread) that started us
    if (captureStdout) dup2(pipeFds[1], STDOUT_FILENO);
    else if (logFd >= 0) dup2(logFd, STDOUT_FILENO);
    if (logFd >= 0) dup2(logFd, STDERR_FILENO);
    execv(args[0], args.data());
    std::fprintf(stderr, "exec %s: %s\n", args[0], std::strerror(errno));
    _exit(127);
  }
  if (logFd >= 0) close(logFd);
  if (captureStdout) {
    close(pipeFds[1]);
    stdoutFd_ = pipeFds[0];
  }
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0 && !exitCode_) {
    ::kill(pid_, SIGKILL);
    wait(std::chrono::seconds(10));
  }
  if (stdoutFd_ >= 0) close(stdoutFd_);
}

ChildProcess::ChildProcess(ChildProcess&& o) noexcept { *this = std::move(o); }
ChildProcess& ChildProcess::operator=(ChildProcess&& o) noexcept {
  std::swap(pid_, o.pid_);
  std::swap(stdoutFd_, o.stdoutFd_);
  std::swap(buffer_, o.buffer_);
  std::swap(exitCode_, o.exitCode_);
  return *this;
}

bool ChildProcess::running() { return pid_ > 0 && !wait(std::chrono::milliseconds(0)); }

std::optional<std::string> ChildProcess::readLine(std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (true) {
    size_t nl = buffer_.find('\n');
    if (nl != std::string::npos) {
      std::string line = buffer_.substr(0, nl);
      buffer_.erase(0, nl + 1);
      return line;
    }
    if (stdoutFd_ < 0) return std::nullopt;
    auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
    if (left.count() <= 0) return std::nullopt;
    pollfd p{stdoutFd_, POLLIN, 0};
    int r = poll(&p, 1, int(left.count()));
    if (r <= 0) continue;
    char buf[4096];
    ssize_t n = read(stdoutFd_, buf, sizeof buf);
    if (n <= 0) {
      close(stdoutFd_);
      stdoutFd_ = -1;
      continue;
    }
    buffer_.append(buf, size_t(n));
  }
}

void ChildProcess::signal(int sig) {
  if (pid_ > 0 && !exitCode_) ::kill(pid_, sig);
}

std::optional<int> ChildProcess::wait(std::chrono::milliseconds timeout) {
  if (exitCode_) return exitCode_;
  if (pid_ <= 0) return std::nullopt;
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (true) {
    int status = 0;
    pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      exitCode_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return exitCode_;
    }
    if (r < 0) {
      exitCode_ = -1;
      return exitCode_;
    }
    if (std::chrono::steady_clock::now() >= end) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

int ChildProcess::terminate(std::chrono::milliseconds grace) {
  signal(SIGTERM);
  if (auto c = wait(grace)) return *c;
  signal(SIGKILL);
  return wait(std::chrono::seconds(30)).value_or(-1);
}

CoordinatorProcess startCoordinatorProcess(const std::string& binary, const std::vector<std::string>& extraArgs,
                                           const std::string& logFile, std::chrono::milliseconds timeout) {
  std::vector<std::string> argv{binary, "--listen", "127.0.0.1:0"};
  argv.insert(argv.end(), extraArgs.begin(), extraArgs.end());
  CoordinatorProcess c{ChildProcess(argv, logFile, true), ""};
  while (auto line = c.process.readLine(timeout)) {
    const std::string prefix = "listening on ";
    if (line->rfind(prefix, 0) == 0) {
      c.address = line->substr(prefix.size());
      return c;
    }
  }
  throw std::runtime_error(fmt::format("{} did not start (see {})", binary, logFile.empty() ? "stderr" : logFile));
}

std::string farmBinaryDir() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("MLTFARM_BIN_DIR")) return env;
  std::error_code ec;
  fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec && fs::exists(self.parent_path() / "mltfarm-coordinator")) return self.parent_path().string();
#ifdef MLTFARM_BINARY_DIR
  return MLTFARM_BINARY_DIR;
#else
  return self.parent_path().string();
#endif
}

}  // namespace mlt::farm
