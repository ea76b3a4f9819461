#include "pipeline/run_folder.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <vector>

#include "pipeline/frame_range.h"
#include "core/atomic_file.h"

namespace confluent {
namespace fs = std::filesystem;

std::string RunFolder::Path(const std::string& relative) const { return (fs::path(root) / relative).string(); }

std::string RunFolder::MaskPath(const std::string& camera, int frame) const {
  return Path("masks/" + camera + "/" + FrameStem(frame) + ".png");
}
std::string RunFolder::TrackingStatePath(int frame) const { return Path("tracking/" + FrameStem(frame) + ".json"); }
std::string RunFolder::TemplatePath(int frame) const { return Path("template/" + FrameStem(frame) + ".ply"); }
std::string RunFolder::ScanPath(int frame) const { return Path("scan/" + FrameStem(frame) + ".ply"); }
std::string RunFolder::RenderPath(const std::string& view, int frame) const {
  return Path("renders/" + view + "/" + FrameStem(frame) + ".png");
}
std::string RunFolder::VideoPath(const std::string& view) const { return Path("renders/" + view + ".mp4"); }

int RemoveStaleTemporaries(const std::string& root) {
  int removed = 0;
  std::error_code error;
  std::vector<fs::path> stale;
  for (auto it = fs::recursive_directory_iterator(root, error); !error && it != fs::recursive_directory_iterator();
       it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(".tmp", 0) != 0) continue;
    const std::size_t underscore = name.find('_', 4);
    if (underscore == std::string::npos || underscore == 4 ||
        name.find_first_not_of("0123456789", 4) != underscore)
      continue;
    const long pid = std::strtol(name.c_str() + 4, nullptr, 10);
    // Alive (or not ours to signal): keep. Our own pid has written nothing yet.
    if (pid == getpid() || pid <= 0 || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    stale.push_back(it->path());
  }
  for (const fs::path& path : stale) removed += fs::remove(path, error) ? 1 : 0;
  return removed;
}

TimingLog::TimingLog(std::string path) : path_(std::move(path)) {
  if (!fs::exists(path_)) return;
  std::istringstream in(ReadTextFile(path_));
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    Row row;
    std::string frame, seconds;
    if (!std::getline(fields, row.stage, ',') || !std::getline(fields, frame, ',') || !std::getline(fields, seconds)) continue;
    try {
      row.frame = std::stoi(frame);
      row.seconds = std::stod(seconds);
    } catch (const std::exception&) {
      continue;  // a damaged row of an interrupted run is dropped, not fatal
    }
    rows_.push_back(row);
  }
}

void TimingLog::Add(const std::string& stage, int frame, double seconds) {
  for (Row& row : rows_)
    if (row.stage == stage && row.frame == frame && frame >= 0) {
      row.seconds = seconds;
      return;
    }
  rows_.push_back({stage, frame, seconds});
}

void TimingLog::Save() const {
  std::ostringstream out;
  out << "stage,frame,seconds\n";
  for (const Row& row : rows_) out << row.stage << "," << row.frame << "," << row.seconds << "\n";
  WriteTextFile(path_, out.str());
}

double TimingLog::StageSeconds(const std::string& stage) const {
  double sum = 0;
  for (const Row& row : rows_)
    if (row.stage == stage) sum += row.seconds;
  return sum;
}

double NowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace confluent
