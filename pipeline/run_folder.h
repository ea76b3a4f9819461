#pragma once
// A run's output folder (docs/ARCHITECTURE.md section 4): the paths of its files, and its timing log.

#include <string>
#include <vector>

namespace confluent {

// Paths inside a run folder. Frame files use six-digit stems (000042.ply).
struct RunFolder {
  std::string root;

  std::string Path(const std::string& relative) const;          // root/relative
  std::string MaskPath(const std::string& camera, int frame) const;   // masks/<cam>/<frame>.png
  std::string TrackingStatePath(int frame) const;                // tracking/<frame>.json
  std::string TemplatePath(int frame) const;                     // template/<frame>.ply
  std::string ScanPath(int frame) const;                         // scan/<frame>.ply
  std::string RenderPath(const std::string& view, int frame) const;  // renders/<view>/<frame>.png
  std::string VideoPath(const std::string& view) const;          // renders/<view>.mp4
};

// Removes the temporary files (`.tmp<pid>_<name>`, see core/atomic_file.h, and ffmpeg's
// `.tmp<pid>_<name>.log`) that a process which no longer runs left under `root`, e.g. a killed
// run. Temporaries of live processes (a shard running beside this one) are kept. Returns how
// many files were removed; errors are ignored (a temporary is never read).
int RemoveStaleTemporaries(const std::string& root);

// timings.csv: one row per stage and frame (frame -1: work of the stage that is not per frame,
// e.g. a factorisation). Reading a stage's inputs and writing its outputs have their own rows
// where they are apart from the computation (e.g. render_read, render, render_write). Rows of
// earlier (resumed) invocations are kept; a frame computed again replaces its row.
class TimingLog {
 public:
  // Loads `path` when it exists (a resumed run).
  explicit TimingLog(std::string path);
  void Add(const std::string& stage, int frame, double seconds);
  // Writes the log atomically (throws OutputError).
  void Save() const;
  // Sum of the seconds of one stage over all rows.
  double StageSeconds(const std::string& stage) const;

  struct Row {
    std::string stage;
    int frame;
    double seconds;
  };
  const std::vector<Row>& rows() const { return rows_; }

 private:
  std::string path_;
  std::vector<Row> rows_;
};

// A monotonic clock in seconds, for stage and frame timings.
double NowSeconds();

}  // namespace confluent
