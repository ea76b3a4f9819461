#pragma once
// Progress reporting from libraries: they call a callback, app/ draws the bar.

#include <cstddef>
#include <functional>
#include <string>

namespace confluent {

// One progress step: `done` of `total` units of `stage` are finished.
struct Progress {
  std::string stage;    // e.g. "silhouettes", "track"
  std::size_t done = 0;
  std::size_t total = 0;
  std::string detail;   // optional short text, e.g. "cam03 frame 12"
};

// Called by long-running library functions; may be empty (no reporting).
using ProgressCallback = std::function<void(const Progress&)>;

// Calls `callback` if it is set.
inline void ReportProgress(const ProgressCallback& callback, const std::string& stage,
                           std::size_t done, std::size_t total, const std::string& detail = {}) {
  if (callback) callback(Progress{stage, done, total, detail});
}

}  // namespace confluent
