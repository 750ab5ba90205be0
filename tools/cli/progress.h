// A progress bar on stderr: "[=====>     ] 12/40 units  30%  ETA 1m05s". Redrawn in place (at most ~10
// times a second) when stderr is a terminal; otherwise silent until finish(), which always prints one
// final line. Thread-safe.
#pragma once
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace mlt::cli {

class ProgressBar {
 public:
  // total: units of work expected (0 = unknown). timeBudgetSeconds > 0: progress is measured by time.
  ProgressBar(std::string label, uint64_t total, double timeBudgetSeconds = 0);
  ~ProgressBar();
  void update(uint64_t done);
  // Prints the final line (always, also when stderr is not a terminal).
  void finish(const std::string& summary);
  static bool stderrIsTerminal();

 private:
  void draw(uint64_t done, bool force);
  std::string label_;
  uint64_t total_;
  double budget_;
  bool tty_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, lastDraw_;
  std::mutex mutex_;
};

std::string formatDuration(double seconds);

}  // namespace mlt::cli
