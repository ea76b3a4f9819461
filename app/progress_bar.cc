#include "app/progress_bar.h"

#include <unistd.h>

#include <cstdio>

namespace confluent::app {

std::string FormatDuration(double seconds) {
  if (!(seconds >= 0)) seconds = 0;
  long total = static_cast<long>(seconds + 0.5);
  char buffer[32];
  if (total >= 3600)
    std::snprintf(buffer, sizeof buffer, "%ld:%02ld:%02ld", total / 3600, (total / 60) % 60, total % 60);
  else
    std::snprintf(buffer, sizeof buffer, "%ld:%02ld", total / 60, total % 60);
  return buffer;
}

ProgressBar::ProgressBar() : is_tty_(isatty(STDERR_FILENO) != 0) {}

void ProgressBar::Update(const Progress& progress) {
  const auto now = std::chrono::steady_clock::now();
  if (progress.stage != stage_) {
    Finish();
    stage_ = progress.stage;
    stage_start_ = now;
    last_draw_ = {};
    last_decile_ = -1;
  }
  const bool done = progress.total > 0 && progress.done >= progress.total;
  const double fraction = progress.total > 0 ? static_cast<double>(progress.done) / progress.total : 0.0;
  const double elapsed = std::chrono::duration<double>(now - stage_start_).count();
  const double rate = elapsed > 0 ? progress.done / elapsed : 0.0;
  const double eta = rate > 0 ? (progress.total - progress.done) / rate : 0.0;
  char numbers[128];
  std::snprintf(numbers, sizeof numbers, "%zu/%zu  %.1f/s  %s %s", progress.done, progress.total, rate,
                done ? "took" : "ETA", FormatDuration(done ? elapsed : eta).c_str());
  if (is_tty_) {
    if (!done && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    const int width = 30;
    const int filled = static_cast<int>(fraction * width);
    std::string bar(filled, '#');
    bar.resize(width, '.');
    std::fprintf(stderr, "\r\033[K%-12s [%s] %s %s", stage_.c_str(), bar.c_str(), numbers, progress.detail.c_str());
    line_open_ = true;
    if (done) Finish();
  } else {
    const int decile = static_cast<int>(fraction * 10);
    if (last_decile_ > 10 || (decile == last_decile_ && !done)) return;
    last_decile_ = decile;
    std::fprintf(stderr, "%-12s %3d%% %s\n", stage_.c_str(), static_cast<int>(fraction * 100), numbers);
    if (done) last_decile_ = 11;  // nothing more for this stage
  }
  std::fflush(stderr);
}

void ProgressBar::Finish() {
  if (line_open_) std::fputc('\n', stderr);
  line_open_ = false;
}

ProgressCallback ProgressBar::AsCallback() {
  return [this](const Progress& progress) { Update(progress); };
}

}  // namespace confluent::app
