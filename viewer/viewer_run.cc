#include "viewer/viewer_run.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "pipeline/frame_range.h"
#include "core/error.h"
#include "core/mesh_io.h"
#include "pipeline/run_manifest.h"

namespace confluent {
namespace fs = std::filesystem;
namespace {

// Frame numbers of the <6 digits>.ply files in `dir`.
std::vector<int> ListFrames(const fs::path& dir) {
  std::vector<int> frames;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return frames;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string stem = entry.path().stem().string();
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext != ".ply" || stem.size() != 6 ||
        !std::all_of(stem.begin(), stem.end(), [](unsigned char c) { return std::isdigit(c); }))
      continue;
    frames.push_back(std::stoi(stem));
  }
  std::sort(frames.begin(), frames.end());
  return frames;
}

}  // namespace

bool ViewerRun::has_frame(int frame) const { return std::binary_search(present.begin(), present.end(), frame); }

std::string ViewerRun::FramePath(int frame) const { return (fs::path(mesh_dir) / (FrameStem(frame) + ".ply")).string(); }

ViewerRun OpenViewerRun(const std::string& root, const std::string& capture_override) {
  std::error_code ec;
  if (!fs::exists(root, ec)) throw InputError(root, "no such run folder");
  if (!fs::is_directory(root, ec)) throw InputError(root, "not a folder (expected a run folder made by confluent run)");
  ViewerRun run;
  run.root = root;
  const std::string json_path = RunManifestPath(root);
  if (!fs::exists(json_path, ec))
    throw InputError(root, "not a run folder: no run.json (make one with: confluent run CAPTURE --out RUN)");
  const RunManifest manifest = ReadRunManifest(json_path);
  run.capture = manifest.capture;
  run.excluded_cameras = manifest.held_out_cameras;
  run.fps = manifest.fps;
  if (!capture_override.empty()) run.capture = capture_override;

  for (const char* kind : {"scan", "template"}) {
    run.present = ListFrames(fs::path(root) / kind);
    if (!run.present.empty()) {
      run.mesh_kind = kind;
      run.mesh_dir = (fs::path(root) / kind).string();
      break;
    }
  }
  if (run.present.empty())
    throw InputError(root, "no frames: neither scan/ nor template/ holds <frame>.ply files (6-digit names)");
  run.first_frame = run.present.front();
  run.last_frame = run.present.back();
  // run.json's frame range [A, B) shows frames that were never written as missing.
  if (manifest.frames.size() > 0 && manifest.frames.size() < 1000000) {
    run.first_frame = std::min(run.first_frame, manifest.frames.first);
    run.last_frame = std::max(run.last_frame, manifest.frames.end - 1);
  }
  return run;
}

FrameCache::FrameCache(const ViewerRun* run, int capacity) : run_(run), capacity_(std::max(1, capacity)) {}

std::shared_ptr<const Mesh> FrameCache::Get(int frame, std::string* error) {
  auto found = entries_.find(frame);
  if (found == entries_.end()) {
    Entry entry;
    const std::string path = run_->FramePath(frame);
    if (!fs::exists(path)) {
      entry.error = "frame " + std::to_string(frame) + " is missing (" + path + ")";
    } else {
      try {
        auto mesh = std::make_shared<Mesh>(ReadMesh(path));
        if (mesh->num_faces() == 0) {
          entry.error = path + ": no faces";
        } else {
          entry.mesh = std::move(mesh);
        }
      } catch (const std::exception& e) {
        entry.error = e.what();
      }
    }
    found = entries_.emplace(frame, std::move(entry)).first;
  }
  recent_.remove(frame);
  recent_.push_front(frame);
  while (static_cast<int>(recent_.size()) > capacity_) {
    entries_.erase(recent_.back());
    recent_.pop_back();
  }
  if (error != nullptr) *error = found->second.error;
  return found->second.mesh;
}

}  // namespace confluent
