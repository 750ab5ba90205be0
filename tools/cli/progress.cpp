// Progress bar on stderr (see progress.h).
#include "tools/cli/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mlt::cli {

std::string formatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  char buf[64];
  if (s >= 3600) std::snprintf(buf, sizeof buf, "%ldh%02ldm%02lds", s / 3600, (s / 60) % 60, s % 60);
  else if (s >= 60) std::snprintf(buf, sizeof buf, "%ldm%02lds", s / 60, s % 60);
  else std::snprintf(buf, sizeof buf, "%.1fs", seconds);
  return buf;
}

bool ProgressBar::stderrIsTerminal() { return isatty(STDERR_FILENO) == 1; }

ProgressBar::ProgressBar(std::string label, uint64_t total, double timeBudgetSeconds)
    : label_(std::move(label)), total_(total), budget_(timeBudgetSeconds), tty_(stderrIsTerminal()),
      start_(std::chrono::steady_clock::now()), lastDraw_(start_) {
  draw(0, true);
}

ProgressBar::~ProgressBar() {
  std::lock_guard lock(mutex_);
  if (tty_ && !finished_) std::fputc('\n', stderr);
}

void ProgressBar::update(uint64_t done) { draw(done, false); }

void ProgressBar::draw(uint64_t done, bool force) {
  std::lock_guard lock(mutex_);
  if (!tty_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (!force && now - lastDraw_ < std::chrono::milliseconds(100) && done < total_) return;
  lastDraw_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  double fraction = 0, eta = NAN;
  if (budget_ > 0) {
    fraction = std::min(1.0, elapsed / budget_);
    eta = std::max(0.0, budget_ - elapsed);
    if (total_ > 0) fraction = std::max(fraction, double(done) / double(total_));
  } else if (total_ > 0) {
    fraction = double(done) / double(total_);
    if (done > 0) eta = elapsed * (double(total_) / double(done) - 1.0);
  }
  constexpr int kWidth = 30;
  const int filled = int(fraction * kWidth);
  std::string bar(kWidth, ' ');
  for (int i = 0; i < filled; ++i) bar[i] = '=';
  if (filled < kWidth) bar[filled] = '>';
  std::fprintf(stderr, "\r%s [%s] %llu/%llu units %3d%%  elapsed %s  ETA %s   ", label_.c_str(), bar.c_str(),
               (unsigned long long)done, (unsigned long long)total_, int(std::lround(fraction * 100)),
               formatDuration(elapsed).c_str(), formatDuration(eta).c_str());
  std::fflush(stderr);
}

void ProgressBar::finish(const std::string& summary) {
  std::lock_guard lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (tty_) std::fputs("\r\033[K", stderr);
  std::fprintf(stderr, "%s\n", summary.c_str());
  std::fflush(stderr);
}

}  // namespace mlt::cli
