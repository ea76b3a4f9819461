#pragma once
// Terminal progress bar with rate and ETA, drawn on stderr.

#include <chrono>
#include <string>

#include "core/progress.h"

namespace confluent::app {

// Draws `Progress` events as "stage [#####.....] 12/40  3.1/s  ETA 0:09" on a tty, redrawn
// in place at most 10 times a second; when stderr is not a tty, prints a plain line at every
// 10% step instead. One bar per stage: a new stage name starts a new line.
class ProgressBar {
 public:
  ProgressBar();
  void Update(const Progress& progress);
  // Ends the current line, if any.
  void Finish();
  ProgressCallback AsCallback();

 private:
  bool is_tty_;
  std::string stage_;
  std::chrono::steady_clock::time_point stage_start_;
  std::chrono::steady_clock::time_point last_draw_;
  int last_decile_ = -1;
  bool line_open_ = false;
};

// Formats seconds as "m:ss" or "h:mm:ss".
std::string FormatDuration(double seconds);

}  // namespace confluent::app
